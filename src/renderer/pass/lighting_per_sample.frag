// Per-sample deferred lighting (methods `per-sample` and `complex`), first
// pass: samples u_first_sample .. u_first_sample + u_sample_count - 1 of the
// multisampled G-buffer, each lit with one batch of lights into its own
// radiance target, o_color[k] for sample u_first_sample + k (outputs past
// u_sample_count write zero, into no draw buffer). The pass is drawn once
// per light batch (and group of SAMPLES_PER_DRAW samples), batches after the
// first added by blending, exactly as the one-sample lighting pass (lighting.frag's main)
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
uniform int u_first_sample;         // the sample o_color[0] lights
uniform int u_sample_count;         // how many outputs are lit

out vec4 o_color[SAMPLES_PER_DRAW];

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
    // One iteration per lit sample: u_sample_count is uniform, so every
    // lane leaves together and no output past it is shaded (a SIMD
    // rasteriser such as llvmpipe runs both sides of a branch, so outputs
    // chosen by a condition would all be shaded). The outputs are picked
    // by constant indices.
    vec4 color[SAMPLES_PER_DRAW];
    for (int k = 0; k < SAMPLES_PER_DRAW; ++k) color[k] = vec4(0.0);
    int count = min(u_sample_count, SAMPLES_PER_DRAW);
    for (int i = 0; i < count; ++i) {
        vec4 c = vec4(shade_sample(pixel, u_first_sample + i), 1.0);
        for (int k = 0; k < SAMPLES_PER_DRAW; ++k) color[k] = k == i ? c : color[k];
    }
    for (int k = 0; k < SAMPLES_PER_DRAW; ++k) o_color[k] = color[k];
}
