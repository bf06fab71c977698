// The forward target's resolve (src/forward.rs): the mean of a pixel's
// samples, in the blend domain of mix_domain.glsl (compiled in front of
// this file), into the host's lit image. A pixel whose every sample still
// holds the lit value the fill put there is one no forward object touched:
// it is left as the host's image has it. That, and a pixel whose samples
// all hold one value (inside a forward object: the mean is that value),
// are decided first, on the samples as fetched; only the pixels on a
// forward object's edge need the blend domain's transfer.
//
// What that saves depends on how the driver runs a shader. A SIMD
// rasterizer (Mesa's llvmpipe: 8 pixels a group) runs every instruction of
// the program once per group whatever its lanes decided, both sides of an
// `if` included; only a loop's later iterations are skipped once no lane
// of the group needs them. So the sRGB transfer (MIX_SRGB_ENCODED) is one
// scalar step inside one loop: a pixel on an edge walks its samples'
// channels through the decode, then its mean's three channels through the
// encode (3 * FORWARD_SAMPLES + 3 steps), and a group with no such pixel
// pays for one step, not for a decode and an encode of three channels. Its
// samples are kept from the test loop rather than fetched again.
// FORWARD_SAMPLES is the target's sample count (a define, so the array has
// a size); u_samples is the same number.

uniform sampler2DMS u_forward;
uniform sampler2D u_lit;
uniform int u_samples;

out vec4 o_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 lit = texelFetch(u_lit, p, 0);
    vec4 first = texelFetch(u_forward, p, 0);
    bool untouched = first == lit;
    bool same = true;
#ifdef MIX_SRGB_ENCODED
    vec4 samples[FORWARD_SAMPLES];
    samples[0] = first;
    for (int s = 1; s < FORWARD_SAMPLES; s++) {
        samples[s] = texelFetch(u_forward, p, s);
        untouched = untouched && samples[s] == lit;
        same = same && samples[s] == first;
    }
#else
    for (int s = 1; s < u_samples; s++) {
        vec4 c = texelFetch(u_forward, p, s);
        untouched = untouched && c == lit;
        same = same && c == first;
    }
#endif
    if (untouched) discard;
    float n = float(u_samples);
#ifdef MIX_SRGB_ENCODED
    // Step k of an edge pixel: channel `channel` of sample `s`, decoded and
    // summed while s < FORWARD_SAMPLES, then channel `channel` of the mean,
    // encoded. A pixel with one value takes no step and keeps `first`.
    int steps = same ? 0 : 3 * FORWARD_SAMPLES + 3;
    vec3 sum = vec3(0.0);
    float alpha = 0.0;
    vec4 result = first;
    int s = 0;
    int channel = 0;
    for (int k = 0; k < steps; k++) {
        bool encode = s == FORWARD_SAMPLES;
        vec4 c = samples[min(s, FORWARD_SAMPLES - 1)];
        float y = srgb_transfer(encode ? sum[channel] / n : c[channel], encode);
        if (encode) {
            result[channel] = y;
        } else {
            sum[channel] += y;
            alpha += channel == 0 ? c.a : 0.0;
        }
        channel++;
        if (channel == 3) {
            channel = 0;
            s++;
        }
    }
    if (!same) {
        result.a = alpha / n;
    }
    o_color = result;
#else
    if (same) {
        o_color = first;
        return;
    }
    vec3 sum = vec3(0.0);
    float alpha = 0.0;
    for (int s = 0; s < u_samples; s++) {
        vec4 c = texelFetch(u_forward, p, s);
        sum += to_mix_domain(c.rgb);
        alpha += c.a;
    }
    o_color = vec4(from_mix_domain(sum / n), alpha / n);
#endif
}
