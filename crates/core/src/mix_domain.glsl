// The domain the crate blends lit colours in, shared by the second layer's
// mix (second_layer.frag) and the forward target's resolve
// (forward_resolve.frag); LayerMix picks it (src/second_layer.rs).
//
// Defines: MIX_LINEAR (as stored), MIX_TONEMAPPED (T(x) = x / (1 +
// max3(x)), the resolve's HDR blend domain), MIX_CURVE (the host's
// dmsaa_curve and dmsaa_curve_inverse, compiled in front of this file) or
// MIX_SRGB_ENCODED (sRGB-encoded display values: decoded to linear light
// and encoded again, IEC 61966-2-1's transfer function).

#ifdef MIX_TONEMAPPED
vec3 dmsaa_curve(vec3 x) {
    return x / (1.0 + max(max(x.r, max(x.g, x.b)), 0.0));
}

vec3 dmsaa_curve_inverse(vec3 y) {
    return y / max(1.0 - max(y.r, max(y.g, y.b)), 1e-6);
}
#endif

#ifdef MIX_SRGB_ENCODED
vec3 srgb_decode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec3 srgb_encode(vec3 l) {
    l = clamp(l, 0.0, 1.0);
    return mix(l * 12.92, 1.055 * pow(l, vec3(1.0 / 2.4)) - 0.055, greaterThan(l, vec3(0.0031308)));
}

// One channel through srgb_decode (encode false) or srgb_encode (encode
// true), the same arithmetic with one `pow` for either direction: the
// forward resolve's one transfer step (forward_resolve.frag says why).
float srgb_transfer(float x, bool encode) {
    x = clamp(x, 0.0, 1.0);
    float straight = encode ? x * 12.92 : x / 12.92;
    float curve = pow(encode ? x : (x + 0.055) / 1.055, encode ? 1.0 / 2.4 : 2.4);
    curve = encode ? 1.055 * curve - 0.055 : curve;
    return x > (encode ? 0.0031308 : 0.04045) ? curve : straight;
}
#endif

// Into the blend domain, and back.
vec3 to_mix_domain(vec3 c) {
#if defined(MIX_LINEAR)
    return c;
#elif defined(MIX_SRGB_ENCODED)
    return srgb_decode(c);
#else
    return dmsaa_curve(c);
#endif
}

vec3 from_mix_domain(vec3 c) {
#if defined(MIX_LINEAR)
    return c;
#elif defined(MIX_SRGB_ENCODED)
    return srgb_encode(c);
#else
    return dmsaa_curve_inverse(c);
#endif
}
