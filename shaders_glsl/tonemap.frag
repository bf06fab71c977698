// Tonemap: linear HDR radiance to display-referred sRGB in an RGBA8 target.
// Exposure, then an extended Reinhard curve per channel (reaching 1.0 at
// u_white, so very bright channels desaturate towards white), then the
// sRGB transfer function.

uniform sampler2D u_hdr;
uniform float u_exposure;
uniform float u_white;

out vec4 o_color;

vec3 reinhard_extended(vec3 x, float white) {
    return x * (1.0 + x / (white * white)) / (1.0 + x);
}

vec3 srgb_encode(vec3 linear) {
    vec3 low = linear * 12.92;
    vec3 high = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(low, high, step(vec3(0.0031308), linear));
}

void main() {
    vec3 hdr = texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb * u_exposure;
    // An infinite input saturates to white; NaN (never expected) shows as black.
    hdr = mix(hdr, vec3(0.0), isnan(hdr));
    hdr = clamp(hdr, 0.0, u_white);
    vec3 ldr = clamp(reinhard_extended(hdr, u_white), 0.0, 1.0);
    o_color = vec4(srgb_encode(ldr), 1.0);
}
