// The resolve's sample pattern and crease rule (resolve.frag's part before
// it; docs/resolve.md, "The crease rule"). The CPU reference (cpu/crease.rs's
// crease_side; cpu/mod.rs's standard_sample_positions) is the only other copy.
//
// Defines (src/resolve/key.rs): NUM_SAMPLES, CLUSTER_NORMALS. Defines
// SAMPLE_PATTERN where the count has a standard pattern, and CREASE_RULE
// where the rule can run (a normal attachment too).

// The standard sample pattern (what GL_SAMPLE_POSITION reads on the drivers
// this crate is tested on): offsets from the pixel centre in 1/16 pixel,
// x right, y up. SAMPLE_PATTERN is defined where the count has one.
#if NUM_SAMPLES == 2
#define SAMPLE_PATTERN 1
const vec2 SAMPLE_POS[2] = vec2[2](vec2(4.0, 4.0), vec2(-4.0, -4.0));
#elif NUM_SAMPLES == 4
#define SAMPLE_PATTERN 1
const vec2 SAMPLE_POS[4] = vec2[4](vec2(-2.0, -6.0), vec2(6.0, -2.0), vec2(-6.0, 2.0), vec2(2.0, 6.0));
#elif NUM_SAMPLES == 8
#define SAMPLE_PATTERN 1
const vec2 SAMPLE_POS[8] = vec2[8](vec2(1.0, -3.0), vec2(-1.0, 3.0), vec2(5.0, 1.0), vec2(-3.0, -5.0),
                                   vec2(-5.0, 5.0), vec2(-7.0, -1.0), vec2(3.0, 7.0), vec2(7.0, -7.0));
#elif NUM_SAMPLES == 16
#define SAMPLE_PATTERN 1
const vec2 SAMPLE_POS[16] = vec2[16](vec2(1.0, 1.0), vec2(-1.0, -3.0), vec2(-3.0, 2.0), vec2(4.0, -1.0),
                                     vec2(-5.0, -2.0), vec2(2.0, 5.0), vec2(5.0, 3.0), vec2(3.0, -5.0),
                                     vec2(-2.0, 6.0), vec2(0.0, -7.0), vec2(-4.0, -6.0), vec2(-6.0, 4.0),
                                     vec2(-8.0, 0.0), vec2(7.0, -4.0), vec2(6.0, 7.0), vec2(-7.0, -8.0));
#endif

#if defined(CLUSTER_NORMALS) && defined(SAMPLE_PATTERN)
#define CREASE_RULE 1
uniform float u_tan_half_fov_y;  // tan(fov_y / 2): the view ray through a window position

// Which of two clusters of samples, a crease's two faces, the pixel centre
// sees: +1 the cluster of sample a (its samples the bits of in_a), -1 that
// of sample b, 0 not known (and 0 at once where open is false). depth holds
// the depth samples, inv_w_terms how one turns into an inverse view
// distance (depth * x + y; affine in window position over a plane), normals
// each sample's view-space normal. Each face is the plane through its
// sample a (or b) with that sample's normal; the crease is where their
// inverse distances are equal, and the centre sees the face on whose side
// of that line it lies. Known only where each face's samples lie on its
// plane to within the gap the centre shows, and the two faces' samples lie
// on opposite sides (two faces that do not meet within the pixel, a
// silhouette, are not a crease). The sample loop starts at start (0, from
// a uniform) so that a SIMD group with no tie leaves it after its first
// iteration.
int crease_side(bool open, int start, float depth[NUM_SAMPLES], vec2 inv_w_terms,
                vec3 normals[NUM_SAMPLES], int a, int in_a, int b, int in_b, vec2 frag_coord, vec2 size) {
    float t = u_tan_half_fov_y;
    float step = 2.0 * t / size.y;  // the ray's change per pixel
    vec3 centre = vec3((2.0 * frag_coord.x / size.x - 1.0) * t * size.x / size.y,
                       (2.0 * frag_coord.y / size.y - 1.0) * t, -1.0);
    vec3 n_a = normals[0];
    vec3 n_b = normals[0];
    float d_a = depth[0];
    float d_b = depth[0];
    vec2 o_a = SAMPLE_POS[0];
    vec2 o_b = SAMPLE_POS[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        n_a = i == a ? normals[i] : n_a;
        n_b = i == b ? normals[i] : n_b;
        d_a = i == a ? depth[i] : d_a;
        d_b = i == b ? depth[i] : d_b;
        o_a = i == a ? SAMPLE_POS[i] : o_a;
        o_b = i == b ? SAMPLE_POS[i] : o_b;
    }
    float w_a = d_a * inv_w_terms.x + inv_w_terms.y;
    float w_b = d_b * inv_w_terms.x + inv_w_terms.y;
    // A plane's inverse distance along ray v is k * dot(n, v).
    float k_a = w_a / dot(n_a, centre + step * vec3(o_a / 16.0, 0.0));
    float k_b = w_b / dot(n_b, centre + step * vec3(o_b / 16.0, 0.0));
    float residual = 0.0;
    float g_a = 0.0;
    float g_b = 0.0;
    for (int s = start; s < NUM_SAMPLES; ++s) {
        if (!open) break;
        vec3 ray = centre + step * vec3(SAMPLE_POS[s] / 16.0, 0.0);
        float w_s = depth[s] * inv_w_terms.x + inv_w_terms.y;
        float on_a = k_a * dot(n_a, ray);
        float on_b = k_b * dot(n_b, ray);
        bool of_a = ((in_a >> s) & 1) != 0;
        bool of_b = ((in_b >> s) & 1) != 0;
        residual += of_a ? abs(on_a - w_s) : 0.0;
        residual += of_b ? abs(on_b - w_s) : 0.0;
        g_a += of_a ? w_s - on_b : 0.0;
        g_b += of_b ? on_a - w_s : 0.0;
    }
    float g_c = k_a * dot(n_a, centre) - k_b * dot(n_b, centre);
    // Well above float rounding of the inverse distances.
    float noise = 1e-5 * max(abs(w_a), abs(w_b));
    bool crease = (g_a > noise && g_b < -noise) || (g_a < -noise && g_b > noise);
    bool clear = abs(g_c) > residual + noise;
    return open && crease && clear ? ((g_c > 0.0) == (g_a > 0.0) ? 1 : -1) : 0;
}
#endif
