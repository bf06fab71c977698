// Tonemap: linear HDR radiance to display-referred sRGB in an RGBA8 target.
// Exposure, then an extended Reinhard curve per channel (reaching 1.0 at
// u_white, so very bright channels desaturate towards white), then the
// sRGB transfer function.
//
// The first part (the curve, its inverse and the sRGB encoding) is shared
// with the per-sample lighting pass, which compiles this file with
// TONEMAP_FUNCTIONS_ONLY defined to average its samples as this pass will
// see them (lighting_per_sample.frag).

#ifdef TONEMAP_CONSTANTS
// The retrofit's layer mix compiles the curve without uniforms (tonemap.rs's
// layer_mix_curve): the renderer's exposure and white point as constants.
const float u_exposure = TONEMAP_EXPOSURE;
const float u_white = TONEMAP_WHITE;
#else
uniform float u_exposure;
uniform float u_white;
#endif

vec3 reinhard_extended(vec3 x, float white) {
    return x * (1.0 + x / (white * white)) / (1.0 + x);
}

// The inverse of reinhard_extended on [0, white] (y in [0, 1]): the
// non-negative root of x^2 / white^2 + (1 - y) x - y = 0.
vec3 reinhard_extended_inverse(vec3 y, float white) {
    float w2 = white * white;
    vec3 b = 1.0 - y;
    return 0.5 * w2 * (sqrt(b * b + 4.0 * y / w2) - b);
}

// HDR radiance to the linear display value this pass encodes as sRGB.
vec3 tonemap_linear(vec3 hdr) {
    hdr *= u_exposure;
    // An infinite input saturates to white; NaN (never expected) shows as black.
    hdr = mix(hdr, vec3(0.0), isnan(hdr));
    hdr = clamp(hdr, 0.0, u_white);
    return clamp(reinhard_extended(hdr, u_white), 0.0, 1.0);
}

// An HDR radiance that tonemap_linear maps to y (in [0, 1]).
vec3 tonemap_linear_inverse(vec3 y) {
    return reinhard_extended_inverse(clamp(y, 0.0, 1.0), u_white) / max(u_exposure, 1e-20);
}

vec3 srgb_encode(vec3 linear) {
    vec3 low = linear * 12.92;
    vec3 high = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(low, high, step(vec3(0.0031308), linear));
}

#ifndef TONEMAP_FUNCTIONS_ONLY

uniform sampler2D u_hdr;

out vec4 o_color;

void main() {
    vec3 hdr = texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb;
    o_color = vec4(srgb_encode(tonemap_linear(hdr)), 1.0);
}

#endif
