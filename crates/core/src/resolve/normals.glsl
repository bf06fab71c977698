// The resolve's normals (resolve.frag's part before it; docs/resolve.md,
// "The math"): how a stored normal decodes, and when two samples' normals
// make them different surfaces. The CPU reference (cpu.rs's
// NormalEncoding::decode and same_normal) is the only other copy.
//
// Defines (src/resolve/key.rs): CLUSTER_NORMALS (a normal attachment is
// named) and NORMAL_ENCODING (NORMAL_XYZ, NORMAL_UNORM, NORMAL_OCTAHEDRAL
// or NORMAL_OCTAHEDRAL_UNORM).

#ifdef CLUSTER_NORMALS
uniform float u_normal_threshold;
#endif

#define NORMAL_XYZ 0
#define NORMAL_UNORM 1
#define NORMAL_OCTAHEDRAL 2
#define NORMAL_OCTAHEDRAL_UNORM 3

// A stored normal as a vector (cpu.rs: NormalEncoding::decode).
vec3 decode_normal(vec4 v) {
#if !defined(NORMAL_ENCODING) || NORMAL_ENCODING == NORMAL_XYZ
    return v.xyz;
#elif NORMAL_ENCODING == NORMAL_UNORM
    return v.xyz * 2.0 - 1.0;
#else
#if NORMAL_ENCODING == NORMAL_OCTAHEDRAL
    vec2 e = v.xy;
#else
    vec2 e = v.xy * 2.0 - 1.0;
#endif
    float z = 1.0 - abs(e.x) - abs(e.y);
    vec2 s = vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
    vec2 folded = (1.0 - abs(e.yx)) * s;
    return vec3(z < 0.0 ? folded : e, z);
#endif
}

// Samples with normals a and b (background flags bg_a, bg_b) may be one
// surface: background, a normal that is not finite or is shorter than 1e-6,
// or a cosine of at least the threshold (cpu.rs's same_normal).
bool same_normal(vec3 a, vec3 b, bool bg_a, bool bg_b) {
#ifdef CLUSTER_NORMALS
    float la = length(a);
    float lb = length(b);
    bool unusable = !(la >= 1e-6) || !(lb >= 1e-6) || isinf(la) || isinf(lb);
    return bg_a || bg_b || unusable || dot(a, b) / (la * lb) >= u_normal_threshold;
#else
    return true;
#endif
}
