// Copies one sample (or the single texel) of a texture into an RGBA32F
// target, so every sample of every attachment can be read back on the CPU.
// Defines: SRC_SAMPLER (sampler2D, sampler2DMS, sampler2DArray, with a u/i
// prefix for integer formats) and one of SRC_MS, SRC_ARRAY or neither.

uniform SRC_SAMPLER u_src;
uniform int u_sample;
out vec4 o_value;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
#if defined(SRC_MS)
    o_value = vec4(texelFetch(u_src, p, u_sample));
#elif defined(SRC_ARRAY)
    o_value = vec4(texelFetch(u_src, ivec3(p, u_sample), 0));
#else
    o_value = vec4(texelFetch(u_src, p, 0));
#endif
}
