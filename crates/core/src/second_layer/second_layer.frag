// The second layer's mix: the lit first layer and the lit second layer,
// mixed by the second layer's coverage (src/second_layer.rs) in the domain
// mix_domain.glsl (compiled in front of this file) defines. A pixel with
// one cluster (coverage 0) keeps the first layer exactly.

uniform sampler2D u_first;
uniform sampler2D u_second;
uniform sampler2D u_coverage;

out vec4 o_color;

bool finite(vec4 v) {
    return !any(isnan(v)) && !any(isinf(v));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 first = texelFetch(u_first, p, 0);
    vec4 second = texelFetch(u_second, p, 0);
    float alpha = clamp(texelFetch(u_coverage, p, 0).r, 0.0, 1.0);
    vec4 mixed = vec4(from_mix_domain(mix(to_mix_domain(first.rgb), to_mix_domain(second.rgb), alpha)),
                      mix(first.a, second.a, alpha));
    // A second lighting that wrote nothing usable leaves the first layer.
    o_color = alpha > 0.0 && finite(second) && finite(mixed) ? mixed : first;
}
