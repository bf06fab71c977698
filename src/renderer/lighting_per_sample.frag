// Per-sample deferred lighting (methods `per-sample` and `complex`), first
// pass: one sample of the multisampled G-buffer, u_sample, lit with one
// batch of lights into that sample's own radiance target. The pass is drawn
// once per sample and light batch, batches after the first added by
// blending, exactly as the one-sample lighting pass (lighting.frag's main)
// adds its batches into the HDR target: each sample's radiance is the sum
// the one-sample pass would store for that G-buffer sample, rounded where
// it rounds. sample_average.frag then tonemaps and averages the samples.
//
// Compiled after lighting.frag (with LIGHTING_FUNCTIONS_ONLY, the same
// MAX_LIGHTS and light uniforms as the one-sample pass). The lighting math is
// lighting.frag's only: shade_surface() / shade_background().

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
uniform int u_sample;               // the sample this draw lights

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

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int i = u_sample;
    if (texelFetch(u_depth, pixel, i).r == u_clear_depth) {
        o_color = vec4(shade_background(sample_emissive(pixel, i, true)), 1.0);
        return;
    }
    vec3 radiance = shade_surface(
        texelFetch(u_color, pixel, i).rgb,
        texelFetch(u_position, pixel, i).xyz,
        texelFetch(u_normal, pixel, i),
        sample_specular(pixel, i),
        sample_emissive(pixel, i, false));
    o_color = vec4(radiance, 1.0);
}
