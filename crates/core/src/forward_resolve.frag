// The forward target's resolve (src/forward.rs): the mean of a pixel's
// samples, in the blend domain of mix_domain.glsl (compiled in front of
// this file), into the host's lit image. A pixel whose every sample still
// holds the lit value the fill put there is one no forward object touched:
// it is left as the host's image has it. That, and a pixel whose samples
// all hold one value (inside a forward object: the mean is that value),
// are decided first, on the samples as fetched, so that only the pixels
// on a forward object's edge pay for the blend domain's transfer (the sRGB
// decode and encode of MIX_SRGB_ENCODED, a host's curve): the resolve's
// cost follows the pixels the forward objects touch.

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
    for (int s = 1; s < u_samples; s++) {
        vec4 c = texelFetch(u_forward, p, s);
        untouched = untouched && c == lit;
        same = same && c == first;
    }
    if (untouched) discard;
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
    float n = float(u_samples);
    o_color = vec4(from_mix_domain(sum / n), alpha / n);
}
