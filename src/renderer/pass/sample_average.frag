// Per-sample deferred lighting (methods `per-sample` and `complex`), second
// pass: the samples' radiance (lighting_per_sample.frag, one layer of
// u_radiance per sample, every light already added) averaged as the tonemap
// pass will see them. The samples are tonemapped (tonemap_linear), averaged,
// and mapped back to HDR (tonemap_linear_inverse), so the tonemapped pixel
// is the box filter of its tonemapped samples, as a supersampled image's is.
// A plain HDR average would let one bright sample (a sky behind a thin wire)
// wash out the others. Pixels whose samples all hold the same radiance pass
// it through unchanged: there the pixel is what one-sample lighting gives
// (and values beyond the tonemap's white stay as they are).
//
// Compiled after tonemap.frag (with TONEMAP_FUNCTIONS_ONLY).

uniform sampler2DArray u_radiance;  // layer i: sample i's radiance
uniform int u_samples;              // samples 0 .. u_samples-1 are averaged

out vec4 o_color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int n = max(u_samples, 1);
    vec3 first = texelFetch(u_radiance, ivec3(pixel, 0), 0).rgb;
    vec3 sum = tonemap_linear(first);
    bool same = true;
    for (int i = 1; i < n; ++i) {
        vec3 radiance = texelFetch(u_radiance, ivec3(pixel, i), 0).rgb;
        same = same && radiance == first;
        sum += tonemap_linear(radiance);
    }
    if (same) {
        o_color = vec4(first, 1.0);
    } else {
        o_color = vec4(tonemap_linear_inverse(sum / float(n)), 1.0);
    }
}
