// The forward target's fill (src/forward.rs): the host's lit image into
// every sample of the multisampled forward target, before the host draws
// its forward objects into it. Read and written the way the host's writes
// were made (decoded and encoded again where they went through the sRGB
// encoding), so that forward_resolve.frag finds untouched samples equal to
// the lit copy.

uniform sampler2D u_lit;

out vec4 o_color;

void main() {
    o_color = texelFetch(u_lit, ivec2(gl_FragCoord.xy), 0);
}
