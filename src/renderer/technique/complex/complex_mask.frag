// Complex-pixel detection of method `complex`: a full-screen pass over the
// multisampled G-buffer that keeps (and so marks in the stencil buffer) the
// pixels whose samples are not all the same surface, and discards the rest.
//
// A pixel is complex when
//   - COVERAGE: a sample's coverage flag (geometry_coverage.frag) is set: a
//     triangle edge crosses the pixel;
//   - complex.glsl's dmsaa_same_surface_within fails for a sample: some
//     samples are background and others are not, or a sample's depth
//     differs from sample 0's by more than u_depth_tolerance pixel
//     footprints (distance x u_footprint). Background is position.w = 0 (the
//     G-buffer pass clears it to 0 and geometry.frag writes 1), not the
//     resolve's clear depth: the pass reads no depth, and kept its masks;
//   - a sample's normal is more than acos(u_normal_cos) away from sample 0's;
//   - a sample's base colour differs from sample 0's by more than
//     u_color_tolerance in a channel.
// The last three catch what coverage misses (triangles that intersect:
// both cover the whole pixel, the depth test splits it) and are all there is
// without gl_SampleMaskIn.

uniform sampler2DMS u_position;
uniform sampler2DMS u_normal;
uniform sampler2DMS u_color;
#ifdef COVERAGE
uniform sampler2DMS u_coverage;
#endif
uniform int u_samples;
uniform float u_footprint;        // tan(fov_y / height_px): pixel size per unit distance
uniform float u_depth_tolerance;  // in pixel footprints
uniform float u_normal_cos;
uniform float u_color_tolerance;

vec3 unit_normal(vec3 n) {
    float len = length(n);
    return len > 1e-6 ? n / len : vec3(0.0, 0.0, 1.0);
}

bool is_complex(ivec2 pixel) {
#ifdef COVERAGE
    for (int i = 0; i < u_samples; ++i) {
        if (texelFetch(u_coverage, pixel, i).r > 0.5) {
            return true;
        }
    }
#endif
    vec4 p0 = texelFetch(u_position, pixel, 0);
    bool background0 = p0.w == 0.0;
    float z0 = -p0.z;
    vec3 n0 = unit_normal(texelFetch(u_normal, pixel, 0).xyz);
    vec3 c0 = texelFetch(u_color, pixel, 0).rgb;
    for (int i = 1; i < u_samples; ++i) {
        vec4 p = texelFetch(u_position, pixel, i);
        bool background = p.w == 0.0;
        float z = -p.z;
        // complex.glsl's test, with a depth tolerance (see there).
        if (!dmsaa_same_surface_within(background, z, background0, z0,
                                       u_depth_tolerance * u_footprint)) {
            return true;
        }
        if (background) {
            continue;
        }
        if (dot(unit_normal(texelFetch(u_normal, pixel, i).xyz), n0) < u_normal_cos) {
            return true;
        }
        vec3 c = texelFetch(u_color, pixel, i).rgb;
        if (any(greaterThan(abs(c - c0), vec3(u_color_tolerance)))) {
            return true;
        }
    }
    return false;
}

void main() {
    if (!is_complex(ivec2(gl_FragCoord.xy))) {
        discard;
    }
}
