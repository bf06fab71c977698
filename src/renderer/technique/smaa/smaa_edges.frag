// SMAA pass 1, edge detection. Each pixel records whether its left (.r) and
// top (.g) boundaries are edges: where the compared value (luma, or each
// colour channel, of the sRGB-encoded image; or the view distance) changes
// across the boundary by at least the threshold. For luma and colour, an
// edge must also be at least 1/LOCAL_CONTRAST of the largest change around
// the pixel (its other two boundaries, and the next boundary out to the left
// and above): beside a strong step, a weak one is shading, not an edge, and
// smoothing it would smear the strong one's neighbourhood.
// Pixels with neither edge are discarded, so the cleared target keeps 0.

uniform sampler2D u_image;     // the tonemapped image, texel for texel
uniform sampler2D u_depth;     // the G-buffer's depth (depth mode only)
uniform int u_mode;            // 0 luma, 1 colour, 2 depth
uniform float u_threshold;
uniform vec2 u_to_ndc;         // depth -> NDC z: scale, offset
uniform vec4 u_unproject;      // NDC z -> view z, w (inverse projection rows)

out vec2 o_edges;

#define LOCAL_CONTRAST 2.0

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);

// The compared value at `p` (clamped to the image: outside, nothing changes).
vec3 value_at(ivec2 p) {
    p = clamp(p, ivec2(0), textureSize(u_image, 0) - 1);
    if (u_mode == 2) {
        float ndc = texelFetch(u_depth, p, 0).r * u_to_ndc.x + u_to_ndc.y;
        float z = u_unproject.x * ndc + u_unproject.y;
        float w = u_unproject.z * ndc + u_unproject.w;
        // The inverse of the view distance: 0 at infinity (the background
        // of an infinite projection), so no division by zero.
        float inverse = z != 0.0 ? max(-w / z, 0.0) : 0.0;
        return vec3(inverse);
    }
    vec3 c = texelFetch(u_image, p, 0).rgb;
    return u_mode == 0 ? vec3(dot(c, LUMA)) : c;
}

// How much the value changes from `a` to `b`.
float change(vec3 a, vec3 b) {
    if (u_mode == 2) {
        // Relative to the nearer: |1/a - 1/b| / (1/max) = |a - b| / min(a, b)
        // in inverse distances.
        float lo = min(a.x, b.x);
        float d = abs(a.x - b.x);
        return lo > 0.0 ? d / lo : (d > 0.0 ? 1e6 : 0.0);
    }
    vec3 d = abs(a - b);
    return max(d.r, max(d.g, d.b));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 here = value_at(p);
    vec3 left = value_at(p + ivec2(-1, 0));
    vec3 top = value_at(p + ivec2(0, 1));
    vec2 delta = vec2(change(here, left), change(here, top));
    vec2 edges = step(vec2(u_threshold), delta);
    if (edges.x + edges.y == 0.0) {
        discard;
    }
    if (u_mode != 2) {
        float right = change(here, value_at(p + ivec2(1, 0)));
        float bottom = change(here, value_at(p + ivec2(0, -1)));
        float far_left = change(left, value_at(p + ivec2(-2, 0)));
        float far_top = change(top, value_at(p + ivec2(0, 2)));
        float largest = max(max(max(delta.x, delta.y), max(right, bottom)),
                            max(far_left, far_top));
        edges *= step(vec2(largest), LOCAL_CONTRAST * delta);
    }
    o_edges = edges;
}
