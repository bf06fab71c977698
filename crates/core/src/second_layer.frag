// The second layer's mix: the lit first layer and the lit second layer,
// mixed by the second layer's coverage (src/second_layer.rs). A pixel with
// one cluster (coverage 0) keeps the first layer exactly.
//
// Defines: MIX_LINEAR, MIX_TONEMAPPED or MIX_CURVE (the host's
// dmsaa_curve and dmsaa_curve_inverse, compiled in front of this file).

uniform sampler2D u_first;
uniform sampler2D u_second;
uniform sampler2D u_coverage;

out vec4 o_color;

#ifdef MIX_TONEMAPPED
// T(x) = x / (1 + max3(x)) and its inverse, the resolve's HDR blend domain.
vec3 dmsaa_curve(vec3 x) {
    return x / (1.0 + max(max(x.r, max(x.g, x.b)), 0.0));
}

vec3 dmsaa_curve_inverse(vec3 y) {
    return y / max(1.0 - max(y.r, max(y.g, y.b)), 1e-6);
}
#endif

bool finite(vec4 v) {
    return !any(isnan(v)) && !any(isinf(v));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 first = texelFetch(u_first, p, 0);
    vec4 second = texelFetch(u_second, p, 0);
    float alpha = clamp(texelFetch(u_coverage, p, 0).r, 0.0, 1.0);
#ifdef MIX_LINEAR
    vec4 mixed = mix(first, second, alpha);
#else
    vec4 mixed = vec4(dmsaa_curve_inverse(mix(dmsaa_curve(first.rgb), dmsaa_curve(second.rgb), alpha)),
                      mix(first.a, second.a, alpha));
#endif
    // A second lighting that wrote nothing usable leaves the first layer.
    o_color = alpha > 0.0 && finite(second) && finite(mixed) ? mixed : first;
}
