// Per-sample deferred lighting (methods `per-sample` and `complex`): every
// sample of the multisampled G-buffer is lit on its own, with every light,
// and the lit samples are averaged, so edges are anti-aliased in the lit
// image rather than in the G-buffer.
//
// Compiled after lighting.frag (with LIGHTING_FUNCTIONS_ONLY and LIGHT_BLOCK:
// all lights in one uniform block, so one draw gives each sample its whole
// radiance) and tonemap.frag (with TONEMAP_FUNCTIONS_ONLY). The lighting
// math is lighting.frag's only: shade_surface() / shade_background().
//
// The average is taken as the tonemap pass will see it: the samples are
// tonemapped (tonemap_linear), averaged, and mapped back to HDR
// (tonemap_linear_inverse), so the tonemapped pixel is the box filter of its
// tonemapped samples, as a supersampled image's is. A plain HDR average
// would let one bright sample (a sky behind a thin wire) wash out the
// others. Pixels whose samples all have the same radiance pass it through
// unchanged (values beyond the tonemap's white stay as they are).
// With more lights than one block holds, the pass draws once per block and
// adds; the average is then linear (u_tonemapped_average = 0), which adds up.

uniform sampler2DMS u_color;
uniform sampler2DMS u_position;
uniform sampler2DMS u_normal;
#ifdef GBUFFER_NO_SPECULAR
uniform vec4 u_specular_constant;   // the one value every material writes
#else
uniform sampler2DMS u_specular;
#endif
#ifdef GBUFFER_NO_EMISSIVE
uniform sampler2D u_background;     // no material emits: the background's own texture
#else
uniform sampler2DMS u_emissive;
#endif
uniform sampler2DMS u_depth;
uniform float u_clear_depth;
uniform int u_samples;              // samples 0 .. u_samples-1 are lit and averaged
uniform int u_tonemapped_average;   // 1: average after the tonemap curve

out vec4 o_color;

// The attachments a scene-adaptive G-buffer may leave out, read as if there.
vec4 sample_specular(ivec2 pixel, int i) {
#ifdef GBUFFER_NO_SPECULAR
    return u_specular_constant;
#else
    return texelFetch(u_specular, pixel, i);
#endif
}

vec3 sample_emissive(ivec2 pixel, int i, bool background) {
#ifdef GBUFFER_NO_EMISSIVE
    // The background copy wrote the same texel into every sample.
    return background ? texelFetch(u_background, pixel, 0).rgb : vec3(0.0);
#else
    return texelFetch(u_emissive, pixel, i).rgb;
#endif
}

vec3 shade_sample(ivec2 pixel, int i) {
    if (texelFetch(u_depth, pixel, i).r == u_clear_depth) {
        return shade_background(sample_emissive(pixel, i, true));
    }
    return shade_surface(
        texelFetch(u_color, pixel, i).rgb,
        texelFetch(u_position, pixel, i).xyz,
        texelFetch(u_normal, pixel, i),
        sample_specular(pixel, i),
        sample_emissive(pixel, i, false));
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int n = max(u_samples, 1);
    vec3 first = shade_sample(pixel, 0);
    vec3 sum = u_tonemapped_average != 0 ? tonemap_linear(first) : first;
    bool same = true;
    for (int i = 1; i < n; ++i) {
        vec3 radiance = shade_sample(pixel, i);
        same = same && radiance == first;
        sum += u_tonemapped_average != 0 ? tonemap_linear(radiance) : radiance;
    }
    vec3 average = sum / float(n);
    if (same) {
        o_color = vec4(first, 1.0);
    } else if (u_tonemapped_average != 0) {
        o_color = vec4(tonemap_linear_inverse(average), 1.0);
    } else {
        o_color = vec4(average, 1.0);
    }
}
