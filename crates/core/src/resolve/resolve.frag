// Depth-aware resolve of a multisampled G-buffer (docs/resolve.md, "The math").
// The CPU reference in src/resolve/cpu.rs implements the same math in f64;
// change both together.
//
// Defines set by src/resolve/mod.rs:
//   NUM_SAMPLES            real sample count N
//   SAMPLES_AS_LAYERS      read a sampler2DArray (one layer per sample) instead of sampler2DMS
//   NUM_ATTACHMENTS        colour attachments 0..7
//   ATTk_SAMPLER, ATTk_VEC sampler and value type of attachment k
//   ATTk_RULE              RULE_BLEND, RULE_BLEND_NORMAL, RULE_BLEND_HDR or RULE_SELECT
//   ATTACHMENT_DECLARATIONS, ATTACHMENT_BEGINS, ATTACHMENT_STEPS, ATTACHMENT_ENDS
//                          the per-attachment code, one template call per attachment
//   KEY_WORLD              the position attachment holds world-space positions:
//                          the key is -dot(u_view_row, (p, 1)), view space's -z
//   KEY_SAMPLER, KEY_INDEX the position attachment's sampler and number, when
//                          the key comes from it (its samples are fetched once)
//   METHOD                 METHOD_AVERAGE, METHOD_FRONT, METHOD_MEDIAN, METHOD_BACK
//                          or METHOD_UPPER_MEDIAN
//   WINDOW_HARD            hard window (smooth otherwise)
//   FAST_PATH              uniform pixels copy sample 0
//   POSITION_UNIFORMITY    with FAST_PATH and KEY_SAMPLER: a pixel is uniform when
//                          the key attachment's samples are all equal; depth
//                          samples 1.. are read only where it is not (opt-in)
//   PLANE_UNIFORMITY, PLANE_SAMPLER
//                          with FAST_PATH: also pixels whose depths fit one plane
//                          and whose PLANE_SAMPLER samples are equal (opt-in)
//   WRITE_DEPTH            write the resolved depth; BLEND_DEPTH blends it
//   COMPLEX_OUTPUT         also write 1.0 for pixels that took the slow path
//   OUTSIDE_OUTPUT         also write 1.0 for pixels a sample of which is outside
//                          the reference's cluster (weight 0): those that may
//                          have a second layer
//   REFERENCE_OUTPUT       also write the reference sample's index (0 for one-sample
//                          pixels): the host's stencil is copied from that sample
//   SELECT_REGION          selective AA: REGION_RECT or REGION_ELLIPSE (u_region)
//   SELECT_MAX_DEPTH       selective AA: pixels with no geometry sample nearer than
//                          u_max_depth take one sample
//   SELECT_FLAG_SAMPLER, SELECT_FLAG_COMPONENT
//                          selective AA: a pixel none of whose samples has this
//                          attachment component >= 0.5 takes one sample
//   CLUSTER_NORMALS, NORMAL_SAMPLER, NORMAL_ENCODING
//                          a normal attachment (one layer or two): samples whose
//                          normals' cosine is below u_normal_threshold are
//                          different surfaces (cpu.rs's same_normal)
//   MAJORITY_REFERENCE     a normal attachment (one layer or two): the reference
//                          moves to the orientation most samples within its
//                          depth window share, a tie to the face the centre
//                          sees (crease.glsl) or by the pixel's parity
//                          (cpu.rs's majority_reference)
//   SECOND_LAYER_OUTPUT    write the second layer (cpu.rs's
//                          resolve_second_layer_at), its coverage to
//                          o_coverage and its depth to o_layer_depth, instead
//                          of the first; ATTACHMENT_ZEROS zeroes the
//                          attachments where there is no second cluster
//   SECOND_LAYER_COLOURS_ONLY  with SECOND_LAYER_OUTPUT: this draw writes
//                          colours only (another writes the coverage and
//                          depth); an attachment not written by this draw
//                          is declared without `out`

#define RULE_BLEND 0
#define RULE_BLEND_NORMAL 1
#define RULE_BLEND_HDR 2
#define RULE_SELECT 3
#define METHOD_AVERAGE 0
#define METHOD_FRONT 1
#define METHOD_MEDIAN 2
#define METHOD_BACK 3
#define METHOD_UPPER_MEDIAN 4
#define REGION_RECT 1
#define REGION_ELLIPSE 2

#ifdef SAMPLES_AS_LAYERS
#define DEPTH_SAMPLER sampler2DArray
#define FETCH(s, p, i) texelFetch(s, ivec3(p, i), 0)
#define TARGET_SIZE textureSize(u_depth, 0).xy
#else
#define DEPTH_SAMPLER sampler2DMS
#define FETCH(s, p, i) texelFetch(s, p, i)
#define TARGET_SIZE textureSize(u_depth)
#endif

uniform DEPTH_SAMPLER u_depth;
uniform float u_clear_depth;     // the background's depth value
uniform vec2 u_depth_to_ndc;     // z_ndc = depth * x + y
uniform vec2 u_projection;       // (p22, p23): distance = p23 / (z_ndc + p22)
uniform float u_footprint;       // tan(fov_y / height_px)
uniform float u_c;               // outer window width, in footprints
uniform float u_c_in;            // inner width of the smooth window
uniform float u_infinity;        // +inf: the sort key of background samples
#ifdef KEY_WORLD
uniform vec4 u_view_row;         // the view matrix's third row: view z of a world position
#endif
#if defined(SELECT_REGION)
uniform vec4 u_region;           // rect (x0, y0, x1, y1); ellipse (cx, cy, 1/rx, 1/ry); window pixels
#endif
#ifdef SELECT_MAX_DEPTH
uniform float u_max_depth;
#endif

// uniform ATTk_SAMPLER u_attk; out ATTk_VEC o_attk; for every attachment k.
ATTACHMENT_DECLARATIONS
#ifdef COMPLEX_OUTPUT
out float o_complex;
#endif
#ifdef OUTSIDE_OUTPUT
out float o_outside;
#endif
#ifdef REFERENCE_OUTPUT
out uint o_reference;
#endif
#if defined(SECOND_LAYER_OUTPUT) && !defined(SECOND_LAYER_COLOURS_ONLY)
out float o_coverage;
out float o_layer_depth;
#elif defined(SECOND_LAYER_OUTPUT)
// Another draw writes these (a host with more colours than draw buffers).
float o_coverage;
float o_layer_depth;
#endif

// Per-pixel state shared by the attachment blocks below.
float g_key[NUM_SAMPLES];      // depth key z_i (meaningless where g_bg)
bool g_bg[NUM_SAMPLES];        // background: clear depth, or a non-finite key
float g_sort[NUM_SAMPLES];     // z_i, or +inf for background: the order of key_less
float g_raw_depth[NUM_SAMPLES];
#ifdef KEY_SAMPLER
vec4 g_key_vals[NUM_SAMPLES];  // the key attachment's samples, fetched once
#endif
// The pixel takes one sample (sample 0 of everything). Set once per pixel,
// before anything but the keys is read.
bool g_one = false;
// 0, unknown to the compiler: loops starting at it are not unrolled (an
// unrolled loop's breaks become nested ifs, which llvmpipe runs in full).
int g_zero = 0;
// OUT = A[I] for a run-time I, by selects over constant indices: an array
// indexed only by constants stays in registers, while one indexed by a
// loop counter that is not unrolled is read lane by lane from memory.
#define PICK(OUT, A, I) OUT = A[0]; for (int k_ = 1; k_ < NUM_SAMPLES; ++k_) OUT = k_ == (I) ? A[k_] : OUT;

// How the work is scheduled (for a SIMD rasteriser as well as for a GPU).
//
// llvmpipe shades 4x2 pixel groups under an execution mask: both sides of
// every `if` run, `discard` saves nothing, and a loop's body runs at least
// once; only a loop iteration that no lane of the group is still in is
// skipped (it tests for an active lane at the end of each iteration). A GPU
// takes real branches, a warp or wave at a time. So everything a
// one-sample pixel does not need lives in loop iterations it leaves:
//
// * sample 0 of every attachment is read before any loop (a one-sample
//   pixel's value); samples 1.. of every attachment, the weights and the
//   blends are one loop over samples 1.. (main), and the reference search
//   is another; both test g_one at the very top of their body, so a group
//   of one-sample pixels runs each body once, masked, and never its later
//   iterations;
// * those loops start at g_zero (0, from a uniform): with a constant start
//   the compiler unrolls them, and an unrolled loop's breaks become nested
//   ifs, which llvmpipe runs in full. Their per-sample values are picked
//   from the constant-indexed arrays by PICK;
// * nothing is written as `if (slow) { ... }` around work: the results are
//   chosen with selects.
//
// Only the keys (depth, or the position attachment, and the depth samples'
// background test) are read in full before g_one is known: whether a pixel
// is uniform depends on all of them.

bool is_finite(vec4 x) {
    return !any(isnan(x)) && !any(isinf(x));
}

#ifdef POSITION_UNIFORMITY
// The key attachment's samples all equal (as floats compare): the opt-in test
// of ResolveSettings::position_uniformity, cpu.rs's position_uniform.
bool g_positions_equal = false;
#endif

// Fill g_raw_depth, g_key, g_bg and g_sort (and the key attachment's samples) for pixel p.
void load_keys(ivec2 p) {
#ifdef POSITION_UNIFORMITY
    // The key attachment first; the depth samples then in a loop that a group
    // of pixels whose positions all agree leaves after sample 0.
    for (int i = 0; i < NUM_SAMPLES; ++i) g_key_vals[i] = FETCH(KEY_SAMPLER, p, i);
    g_positions_equal = true;
    for (int i = 1; i < NUM_SAMPLES; ++i)
        g_positions_equal = g_positions_equal && g_key_vals[i] == g_key_vals[0];
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        g_raw_depth[i] = 0.0;
        g_key[i] = 0.0;
        g_bg[i] = true;
        g_sort[i] = u_infinity;
    }
    for (int i = g_zero; i < NUM_SAMPLES; ++i) {
        float depth = FETCH(u_depth, p, i).r;
        vec4 key;
        PICK(key, g_key_vals, i)
#ifdef KEY_WORLD
        float z = -dot(u_view_row, vec4(key.xyz, 1.0));
#else
        float z = -key.z;
#endif
        bool bg = depth == u_clear_depth || isnan(z) || isinf(z);
        for (int k = 0; k < NUM_SAMPLES; ++k) {
            g_raw_depth[k] = k == i ? depth : g_raw_depth[k];
            g_key[k] = k == i ? z : g_key[k];
            g_bg[k] = k == i ? bg : g_bg[k];
            g_sort[k] = k == i ? (bg ? u_infinity : z) : g_sort[k];
        }
        if (g_positions_equal) break;
    }
#else
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        float depth = FETCH(u_depth, p, i).r;
        g_raw_depth[i] = depth;
#ifdef KEY_SAMPLER
        g_key_vals[i] = FETCH(KEY_SAMPLER, p, i);
#ifdef KEY_WORLD
        float z = -dot(u_view_row, vec4(g_key_vals[i].xyz, 1.0));
#else
        float z = -g_key_vals[i].z;
#endif
#else
        float z = u_projection.y / (depth * u_depth_to_ndc.x + u_depth_to_ndc.y + u_projection.x);
#endif
        g_bg[i] = depth == u_clear_depth || isnan(z) || isinf(z);
        g_key[i] = z;
        g_sort[i] = g_bg[i] ? u_infinity : z;
    }
#endif
}

// key_less(i, j), the strict order by (z, index) with background at
// +infinity, is g_sort[i] < g_sort[j] || (g_sort[i] == g_sort[j] && i < j):
// geometry keys are finite (a non-finite key is background).

// The code below is written with selects rather than branches, and no array
// is indexed by a run-time value (PICK instead): a SIMD rasteriser such as
// llvmpipe runs both sides of every branch that its lanes disagree on, and
// masks every store made inside one.

// The reference sample; 0 for a one-sample pixel.
int reference_sample() {
    int r = 0;
#if METHOD == METHOD_FRONT
    // Nearest; the sweep only replaces r by a higher index, so a tie keeps r.
    float best = g_sort[0];
    for (int i = g_zero + 1; i < NUM_SAMPLES; ++i) {
        if (g_one) break;
        float si;
        PICK(si, g_sort, i)
        bool nearer = si < best;
        r = nearer ? i : r;
        best = nearer ? si : best;
    }
#elif METHOD == METHOD_BACK
    // Farthest; among equal depths the lower index.
    float best = g_sort[0];
    for (int i = g_zero + 1; i < NUM_SAMPLES; ++i) {
        if (g_one) break;
        float si;
        PICK(si, g_sort, i)
        bool farther = si > best;
        r = farther ? i : r;
        best = farther ? si : best;
    }
#else
    // Median (also the average's reference): the sample whose rank under
    // key_less is the median's. Ranks are counted, not sorted, so every
    // sample's own depth decides its place. For an even N the two middle
    // ranks take turns by the pixel's parity (cpu.rs's median_rank), so a
    // half-covered pixel goes to either surface alike; the upper median
    // (FreeSpace Open's) always takes rank N/2.
#if METHOD == METHOD_UPPER_MEDIAN
    int median_rank = NUM_SAMPLES / 2;
#else
    ivec2 place = ivec2(gl_FragCoord.xy);
    int median_rank = (NUM_SAMPLES - 1 + ((place.x + place.y) & 1)) / 2;
#endif
    int ranks[NUM_SAMPLES];
    for (int k = 0; k < NUM_SAMPLES; ++k) ranks[k] = k;
    for (int i = g_zero; i < NUM_SAMPLES; ++i) {
        if (g_one) break;
        float si;
        PICK(si, g_sort, i)
        // key_less(j, i), with sample i's key picked once.
        int rank = 0;
        for (int j = 0; j < NUM_SAMPLES; ++j) rank += g_sort[j] < si || (g_sort[j] == si && j < i) ? 1 : 0;
        for (int k = 0; k < NUM_SAMPLES; ++k) ranks[k] = k == i ? rank : ranks[k];
    }
    for (int k = 0; k < NUM_SAMPLES; ++k) r = ranks[k] == median_rank ? k : r;
    r = g_one ? 0 : r;
#endif
    return r;
}

// Closeness of a sample with key z and background flag bg (is_ref: it is
// the reference) to the reference, whose key and background flag are z_r
// and bg_r.
float closeness(float z, bool bg, bool is_ref, float z_r, bool bg_r) {
#if METHOD == METHOD_AVERAGE
    return 1.0;
#else
    float d = abs(z - z_r);
    // A key at or behind the eye (a position attachment can hold one) has
    // no window, but equal keys are still one surface.
    float m = max(min(z, z_r), 0.0) * u_footprint;
#ifdef WINDOW_HARD
    float w = d <= u_c * m ? 1.0 : 0.0;
#else
    // 1 - smoothstep(t) == smoothstep(1 - t): measure from the outer edge so a
    // weight near 0 is not the difference of two numbers near 1.
    float u = (u_c * m - d) / ((u_c - u_c_in) * m);
    float w = u * u * (3.0 - 2.0 * u);
    w = d >= u_c * m ? 0.0 : w;
    w = d <= u_c_in * m ? 1.0 : w;
#endif
    // Background only with background, geometry only with geometry.
    w = bg || bg_r ? (bg && bg_r ? 1.0 : 0.0) : w;
    return is_ref ? 1.0 : w;
#endif
}

// decode_normal and same_normal: normals.glsl, the part before this one.

#ifdef SECOND_LAYER_OUTPUT
// A sample of neither kept cluster joins the second layer (seeded at z_s)
// rather than the first (reference at z_r): the nearer in depth, background
// at no distance from background and infinitely far from geometry; on a
// tie the closer in orientation, with normals and geometry throughout;
// else the first (cpu.rs's joins_second).
bool joins_second(float z, bool bg, vec3 n, float z_r, bool bg_r, vec3 n_r,
                  float z_s, bool bg_s, vec3 n_s) {
    bool near_first = bg == bg_r;
    bool near_second = bg == bg_s;
    float d_first = abs(z - z_r);
    float d_second = abs(z - z_s);
    bool by_depth = near_first != near_second || (near_first && !bg && d_first != d_second);
    bool second_by_depth = near_first != near_second ? near_second : d_second < d_first;
#ifdef CLUSTER_NORMALS
    float c_first = dot(n, n_r) / (length(n) * length(n_r));
    float c_second = dot(n, n_s) / (length(n) * length(n_s));
    bool second_by_normal = !bg && !bg_r && !bg_s && c_second > c_first;
#else
    bool second_by_normal = false;
#endif
    return by_depth ? second_by_depth : second_by_normal;
}
#endif

float max3(vec3 v) {
    return max(v.x, max(v.y, v.z));
}

// One attachment's running blend, a sample at a time. acc_step and
// acc_finish are the blends of docs/resolve.md's "The math" (the CPU reference's
// blend, blend_normal and blend_hdr), split so that one loop over the
// samples can feed every attachment.
struct Acc {
    vec4 sum;         // weighted sum (RULE_BLEND, RULE_BLEND_NORMAL); xyz tonemapped, w alpha (HDR)
    vec3 complement;  // HDR: the blended 1 - max3(T(x)), per channel
    vec3 lo;          // HDR: the contributing samples' range
    vec3 hi;
    float weight;
    vec4 first;       // the first contributing value, and whether every one equals it:
    bool same;        // a blend of equal values is that value, with no rounding
};

Acc acc_new() {
    return Acc(vec4(0.0), vec3(0.0), vec3(u_infinity), vec3(-u_infinity), 0.0, vec4(0.0), true);
}

// Add sample value x with closeness weight w; non-finite values do not count.
void acc_step(inout Acc a, int rule, vec4 x, float w) {
    bool used = w > 0.0 && is_finite(x);
    bool first = used && a.weight == 0.0;
    a.same = a.same && (!used || first || x == a.first);
    a.first = first ? x : a.first;
    if (rule == RULE_BLEND_HDR) {
        // Blend in the tonemapped domain T(x) = x / (1 + max3(x)) so one
        // bright sample cannot swamp its neighbours; 1 - max3(T) is
        // accumulated directly as the min over channels of the blended
        // (1 + m - x) / (1 + m): the same value, without the cancellation
        // that costs f32 three digits near 65504.
        float m = max(max3(x.rgb), 0.0);
        float wu = used ? w : 0.0;
        a.sum.rgb += used ? wu * (x.rgb / (1.0 + m)) : vec3(0.0);
        a.complement += used ? wu * ((1.0 + m - x.rgb) / (1.0 + m)) : vec3(0.0);
        a.sum.a += used ? wu * x.a : 0.0;
        a.weight += wu;
        a.lo = used ? min(a.lo, x.rgb) : a.lo;
        a.hi = used ? max(a.hi, x.rgb) : a.hi;
    } else {
        a.sum += used ? w * x : vec4(0.0);
        a.weight += used ? w : 0.0;
    }
}

// The blended value; `reference` (the reference sample's) where nothing weighs.
vec4 acc_finish(Acc a, int rule, vec4 reference) {
    if (rule == RULE_BLEND_NORMAL) {
        // Equal normals are kept as written (normalised or not), as RULE_BLEND
        // keeps equal values; else the weighted sum of normals, normalised,
        // and w blends as RULE_BLEND does.
        if (a.weight > 0.0 && a.same) return a.first;
        float len = length(a.sum.xyz);
        float w = a.weight > 0.0 ? a.sum.w / a.weight : reference.w;
        return vec4(len >= 1e-6 ? a.sum.xyz / len : reference.xyz, w);
    }
    if (rule == RULE_BLEND_HDR) {
        // Map back with T^-1(y) = y / (1 - max3(y)), inside the samples' range.
        float denominator = min(min(a.complement.x, a.complement.y), min(a.complement.z, a.weight));
        vec3 x = a.sum.rgb / max(denominator, 1e-30);
        float alpha = a.same ? a.first.a : a.sum.a / a.weight;
        return a.weight > 0.0 ? vec4(clamp(x, a.lo, a.hi), alpha) : reference;
    }
    return a.weight > 0.0 ? (a.same ? a.first : a.sum / a.weight) : reference;
}

// Uniform pixel: every sample is background, or every sample is geometry
// with the same key (complex.glsl's dmsaa_same_surface, composed in front of
// this file; the CPU reference's definition, keep them equal), and with the
// normal test one orientation (one_orientation).
//
// With a position key every depth sample is read too: a sample is background
// by its own depth, and a background sample's position is whatever the host
// cleared it to, which a geometry sample's may equal (position cleared to
// (0, 0, -far): tests/fast/resolve_layers.rs's one-geometry-sample case); a
// sky drawn at the far plane is background in one sample, geometry in the
// next. Equal keys of geometry samples make every weight 1: the CPU
// reference calls such a pixel uniform whatever wrote it.
bool keys_uniform() {
    bool same = true;
#ifdef KEY_WORLD
    // A world-space position: the whole position and the depth sample must
    // agree. A half-float position (the tutorial layout's) rounds samples a
    // quarter pixel apart, on both sides of an edge between coplanar faces,
    // to one value; their depth samples still differ.
    for (int i = 1; i < NUM_SAMPLES; ++i)
        if (!dmsaa_same_surface(g_bg[i], vec4(g_key_vals[i].xyz, g_raw_depth[i]),
                                g_bg[0], vec4(g_key_vals[0].xyz, g_raw_depth[0])))
            same = false;
#else
    for (int i = 1; i < NUM_SAMPLES; ++i)
        if (!dmsaa_same_surface(g_bg[i], g_key[i], g_bg[0], g_key[0])) same = false;
#endif
    return same;
}

#if defined(KEY_SAMPLER) && !defined(KEY_WORLD) && defined(CLUSTER_NORMALS)
// Equal view-space keys are one surface where the depth samples agree too,
// or every normal passes the normal test against sample 0's (cpu.rs's
// one_orientation): a half-float position rounds a ridge's two facets to one
// key, which hid the crease. Normals past sample 0's: only where depths differ.
bool one_orientation(ivec2 p) {
    bool same = true;
    for (int i = 1; i < NUM_SAMPLES; ++i) same = same && g_raw_depth[i] == g_raw_depth[0];
    bool check = !same;
    vec3 n_0 = decode_normal(vec4(FETCH(NORMAL_SAMPLER, p, 0)));
    for (int i = g_zero + 1; i < NUM_SAMPLES; ++i) {
        if (!check) break;
        bool bg_i;
        PICK(bg_i, g_bg, i)
        check = same_normal(decode_normal(vec4(FETCH(NORMAL_SAMPLER, p, i))), n_0, bg_i, g_bg[0]);
        same = check && i == NUM_SAMPLES - 1;
    }
    return same;
}
#endif

#ifdef PLANE_UNIFORMITY
// The opt-in plane test (ResolveSettings::plane_uniformity; cpu.rs's
// plane_fits and plane_uniform are the same test): every sample is geometry,
// the depth samples lie on one plane over the standard sample pattern, and
// the first blended attachment's samples are all equal. One triangle's
// samples pass it; it does not prove that one fragment wrote the pixel.
// The sample pattern is crease.glsl's.

// Least squares over e_i = d_i - d_0 (exact where depths are close), with
// positions and e centred; up to 3 samples always fit, a count without a
// pattern never does.
bool plane_fits() {
#if NUM_SAMPLES <= 3
    return true;
#elif !defined(SAMPLE_PATTERN)
    return false;
#else
    vec2 mean_pos = vec2(0.0);
    float mean_e = 0.0;
    float largest = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        mean_pos += SAMPLE_POS[i];
        mean_e += g_raw_depth[i] - g_raw_depth[0];
        largest = max(largest, abs(g_raw_depth[i]));
    }
    mean_pos /= float(NUM_SAMPLES);
    mean_e /= float(NUM_SAMPLES);
    float sxx = 0.0, sxy = 0.0, syy = 0.0, sxe = 0.0, sye = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        vec2 q = SAMPLE_POS[i] - mean_pos;
        float v = (g_raw_depth[i] - g_raw_depth[0]) - mean_e;
        sxx += q.x * q.x;
        sxy += q.x * q.y;
        syy += q.y * q.y;
        sxe += q.x * v;
        sye += q.y * v;
    }
    float det = sxx * syy - sxy * sxy;
    float b = (syy * sxe - sxy * sye) / det;
    float c = (sxx * sye - sxy * sxe) / det;
    float worst = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        vec2 q = SAMPLE_POS[i] - mean_pos;
        float v = (g_raw_depth[i] - g_raw_depth[0]) - mean_e;
        worst = max(worst, abs(v - b * q.x - c * q.y));
    }
    // 2^-22 * max|d| + 2^-23; a NaN residual fails.
    return worst <= largest * 2.384185791015625e-7 + 1.1920928955078125e-7;
#endif
}

bool plane_uniform(ivec2 p) {
    bool same = true;
    for (int i = 0; i < NUM_SAMPLES; ++i) same = same && !g_bg[i];
    same = same && plane_fits();
    // The attachment is read only while the pixel still passes.
    vec4 first = vec4(FETCH(PLANE_SAMPLER, p, 0));
    for (int i = g_zero + 1; i < NUM_SAMPLES; ++i) {
        if (!same) break;
        same = vec4(FETCH(PLANE_SAMPLER, p, i)) == first;
    }
    return same;
}
#endif

// Selective anti-aliasing: the pixel lies outside what should be anti-aliased.
bool outside_selection(ivec2 p) {
    bool outside = false;
#if defined(SELECT_REGION)
    vec2 c = vec2(p) + 0.5;
#if SELECT_REGION == REGION_RECT
    outside = dmsaa_outside_rect(c, u_region);
#else
    outside = dmsaa_outside_ellipse(c, u_region);
#endif
#endif
#ifdef SELECT_MAX_DEPTH
    bool near = false;
    for (int i = 0; i < NUM_SAMPLES; ++i)
        if (dmsaa_within_depth(g_bg[i], g_key[i], u_max_depth)) near = true;
    outside = outside || !near;
#endif
#ifdef SELECT_FLAG_SAMPLER
    // Read only while the pixel might still be resolved.
    bool wanted = false;
    for (int i = g_zero; i < NUM_SAMPLES; ++i) {
        if (outside) break;
        if (FETCH(SELECT_FLAG_SAMPLER, p, i).SELECT_FLAG_COMPONENT >= 0.5) wanted = true;
    }
    outside = outside || !wanted;
#endif
    return outside;
}

// The pixel takes one sample (sample 0 of everything): it is uniform (with
// the fast path), or outside the selection. Needs load_keys(p) first.
bool takes_one_sample(ivec2 p) {
    bool one = false;
#ifdef FAST_PATH
#ifdef POSITION_UNIFORMITY
    one = g_positions_equal;
#else
    one = keys_uniform();
#if defined(KEY_SAMPLER) && !defined(KEY_WORLD) && defined(CLUSTER_NORMALS)
    one = one && one_orientation(p);
#endif
#endif
#ifdef PLANE_UNIFORMITY
    one = one || plane_uniform(p);
#endif
#endif
#if defined(SELECT_REGION) || defined(SELECT_MAX_DEPTH) || defined(SELECT_FLAG_SAMPLER)
    one = one || outside_selection(p);
#endif
    return one;
}

// The value of the key attachment's sample r, by selects (g_key_vals[0] for r = 0).
vec4 key_value_at(int r) {
    vec4 v = vec4(0.0);
#ifdef KEY_SAMPLER
    v = g_key_vals[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) v = i == r ? g_key_vals[i] : v;
#endif
    return v;
}

// The per-attachment template. src/resolve/mod.rs writes, for each
// attachment k in order, one call of these into ATTACHMENT_BEGINS (before
// the sample loop), ATTACHMENT_STEPS (its body) and ATTACHMENT_ENDS (after
// it): KEY_* for the key attachment, whose samples are already in
// g_key_vals; BLEND_* for a blended one, which fetches sample i in
// iteration i (sample 0, a one-sample pixel's value, in the first) and
// picks up the reference sample's value on the way; SELECT_END alone for a
// Select one, which fetches sample r once after the loop (r is 0 for a
// one-sample pixel).
#define BLEND_BEGIN(S, V, REF, ACC, RULE) vec4 V = vec4(0.0); vec4 REF = vec4(0.0); Acc ACC = acc_new();
#define BLEND_STEP(S, V, REF, ACC, RULE) { vec4 x = vec4(FETCH(S, p, i)); V = i == 0 ? x : V; REF = i == r ? x : REF; acc_step(ACC, RULE, x, w); }
#define BLEND_END(O, V, REF, ACC, RULE) O = g_one ? V : acc_finish(ACC, RULE, REF);
#define KEY_BEGIN(V, REF, ACC, RULE) vec4 V = g_key_vals[0]; vec4 REF = key_value_at(r); Acc ACC = acc_new();
#define KEY_STEP(ACC, RULE) acc_step(ACC, RULE, key_i, w);
#define KEY_END(O, V, REF, ACC, RULE) O = g_one || RULE == RULE_SELECT ? REF : acc_finish(ACC, RULE, REF);
#define SELECT_END(O, S) O = FETCH(S, p, r);

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    g_zero = u_infinity > 0.0 ? 0 : 1;
    load_keys(p);
    g_one = takes_one_sample(p);

    // The reference sample (0 for a one-sample pixel, which leaves the
    // search's loop at once) and its key, background flag and depth.
    int r = reference_sample();
    float z_r = g_key[0];
    bool bg_r = g_bg[0];
    float reference_depth = g_raw_depth[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        z_r = i == r ? g_key[i] : z_r;
        bg_r = i == r ? g_bg[i] : bg_r;
        reference_depth = i == r ? g_raw_depth[i] : reference_depth;
    }
    // Every sample's normal, fetched and decoded once for every step below
    // (n_r's in all of them for a one-sample pixel, whose group leaves the
    // loop after its first iteration), and which samples are within the
    // reference's depth window (near_r) and of its cluster (in_r), as bits.
    vec3 normals[NUM_SAMPLES];
#ifdef CLUSTER_NORMALS
    vec3 n_r = decode_normal(vec4(FETCH(NORMAL_SAMPLER, p, r)));
#else
    vec3 n_r = vec3(0.0);
#endif
    for (int k = 0; k < NUM_SAMPLES; ++k) normals[k] = n_r;
    int near_r = 0;
    int in_r = 0;
#if defined(CLUSTER_NORMALS) || defined(MAJORITY_REFERENCE) || defined(SECOND_LAYER_OUTPUT)
    for (int i = g_zero; i < NUM_SAMPLES; ++i) {
        if (g_one) break;
        float z_i;
        bool bg_i;
        PICK(z_i, g_key, i)
        PICK(bg_i, g_bg, i)
#ifdef CLUSTER_NORMALS
        vec3 n_i = decode_normal(vec4(FETCH(NORMAL_SAMPLER, p, i)));
#else
        vec3 n_i = vec3(0.0);
#endif
        for (int k = 0; k < NUM_SAMPLES; ++k) normals[k] = k == i ? n_i : normals[k];
#if defined(MAJORITY_REFERENCE) || defined(SECOND_LAYER_OUTPUT)
        bool near = closeness(z_i, bg_i, i == r, z_r, bg_r) > 0.0;
        near_r |= near ? 1 << i : 0;
        in_r |= near && same_normal(n_i, n_r, bg_i, bg_r) ? 1 << i : 0;
#endif
    }
#endif
    const int ALL_SAMPLES = (1 << NUM_SAMPLES) - 1;
#if defined(MAJORITY_REFERENCE) || defined(SECOND_LAYER_OUTPUT)
    // The reference's cluster holds every sample: no cluster is larger and
    // none is another orientation (the majority keeps the reference), and
    // there is no second layer. A group of such pixels leaves the loops
    // below after their first iteration.
    bool settled = g_one || in_r == ALL_SAMPLES;
    // The clusters, computed once for the majority and the second layer:
    // bit j of members[s] is set when sample j is within sample s's window
    // and of its orientation (cpu.rs's member); sizes[s] counts them.
    int members[NUM_SAMPLES];
    int sizes[NUM_SAMPLES];
    for (int k = 0; k < NUM_SAMPLES; ++k) {
        members[k] = 0;
        sizes[k] = 0;
    }
    for (int s = g_zero; s < NUM_SAMPLES; ++s) {
        if (settled) break;
        float z_s;
        bool bg_s;
        vec3 n_s;
        PICK(z_s, g_key, s)
        PICK(bg_s, g_bg, s)
        PICK(n_s, normals, s)
        int bits = 0;
        int size = 0;
        for (int j = 0; j < NUM_SAMPLES; ++j) {
            bool member = closeness(g_key[j], g_bg[j], j == s, z_s, bg_s) > 0.0
                && same_normal(normals[j], n_s, g_bg[j], bg_s);
            bits |= member ? 1 << j : 0;
            size += member ? 1 : 0;
        }
        for (int k = 0; k < NUM_SAMPLES; ++k) {
            members[k] = k == s ? bits : members[k];
            sizes[k] = k == s ? size : sizes[k];
        }
    }
#endif
#ifdef MAJORITY_REFERENCE
    // The reference moves to the orientation most samples within its depth
    // window share (cpu.rs's majority_reference). A crease, or a
    // box's side face behind its front face, can put the median on the
    // smaller of two faces, which the larger's samples would then join, lit
    // as it; a tie goes to the face the pixel centre sees where the crease
    // rule knows it, else by the pixel's parity.
    {
        int best = r;
        int best_size;
        PICK(best_size, sizes, r)
        int r_size = best_size;
        // The first sample of another cluster within the window as large
        // as the reference's: where none is larger, taken on pixels of odd
        // parity (cpu.rs's majority_reference says what that does with
        // the median's own tie). Within the window, another orientation is
        // outside the reference's cluster.
        int tied = -1;
        for (int s = g_zero; s < NUM_SAMPLES; ++s) {
            if (settled) break;
            int size_s;
            PICK(size_s, sizes, s)
            bool near = ((near_r >> s) & 1) != 0;
            bool better = near && size_s > best_size;
            best = better ? s : best;
            best_size = better ? size_s : best_size;
            bool tie = near && tied < 0 && size_s == r_size && ((in_r >> s) & 1) == 0;
            tied = tie ? s : tied;
        }
        ivec2 place = ivec2(gl_FragCoord.xy);
        bool tie_open = best == r && tied >= 0 && !settled;
        int side = 0;
#ifdef CREASE_RULE
        int in_tied;
        PICK(in_tied, members, max(tied, 0))
        vec2 inv_w_terms = vec2(u_depth_to_ndc.x, u_depth_to_ndc.y + u_projection.x) / u_projection.y;
        side = crease_side(tie_open, g_zero, g_raw_depth, inv_w_terms, normals, r, in_r, max(tied, 0),
                           in_tied, gl_FragCoord.xy, vec2(TARGET_SIZE));
#endif
        bool take_tie = tie_open && (side < 0 || (side == 0 && ((place.x + place.y) & 1) == 1));
        best = take_tie ? tied : best;
        bool moved = best != r;
        for (int i = 0; i < NUM_SAMPLES; ++i) {
            reference_depth = i == best ? g_raw_depth[i] : reference_depth;
            z_r = i == best ? g_key[i] : z_r;
            bg_r = i == best ? g_bg[i] : bg_r;
            n_r = i == best ? normals[i] : n_r;
        }
        int members_best;
        PICK(members_best, members, best)
        // The moved reference's cluster is its column of the clusters.
        in_r = moved ? members_best : in_r;
        r = best;
    }
#endif

#ifdef SECOND_LAYER_OUTPUT
    // The second layer (cpu.rs's resolve_second_layer_at). The first
    // layer's cluster: the samples its blend weighs (every sample of a
    // one-sample pixel).
    int in_first = g_one ? ALL_SAMPLES : in_r;
    // A pixel all of whose samples are in the first cluster has no second
    // one: its group leaves the loops below after their first iteration.
    bool one_cluster = settled || in_first == ALL_SAMPLES;
    // The second layer's seed, outside it: one outside the reference's
    // depth window (another surface in depth) before one inside it (another
    // orientation at its depth: a crease, a box's side face), then the
    // largest cluster (each candidate's is the outside samples within its
    // window and of its orientation), ties to the nearer seed (candidates
    // come in index order).
    int seed = -1;
    int second_size = 0;
    float seed_sort = 0.0;
    bool seed_apart = false;
    for (int s = g_zero; s < NUM_SAMPLES; ++s) {
        if (one_cluster) break;
        float z_s;
        bool bg_s;
        float sort_s;
        int members_s;
        PICK(z_s, g_key, s)
        PICK(bg_s, g_bg, s)
        PICK(sort_s, g_sort, s)
        PICK(members_s, members, s)
        bool in_s = ((in_first >> s) & 1) != 0;
        int outside = members_s & ~in_first;
        int size = 0;
        for (int j = 0; j < NUM_SAMPLES; ++j) size += (outside >> j) & 1;
        bool apart = !(closeness(z_s, bg_s, s == r, z_r, bg_r) > 0.0);
        bool better = !in_s && (seed < 0 || (apart && !seed_apart) || (apart == seed_apart && (size > second_size || (size == second_size && sort_s < seed_sort))));
        seed_apart = better ? apart : seed_apart;
        seed = better ? s : seed;
        second_size = better ? size : second_size;
        seed_sort = better ? sort_s : seed_sort;
    }
    bool has_second = seed >= 0 && !one_cluster;
    // The samples of neither kept cluster (three surfaces or more) join the
    // nearer layer: no sample's share of the pixel is lost.
    float z_s = 0.0;
    bool bg_s = false;
    vec3 n_s = vec3(0.0);
    int in_second = 0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        z_s = i == seed ? g_key[i] : z_s;
        bg_s = i == seed ? g_bg[i] : bg_s;
        n_s = i == seed ? normals[i] : n_s;
        in_second = i == seed ? members[i] : in_second;
    }
    int joined_second = 0;
    for (int j = g_zero; j < NUM_SAMPLES; ++j) {
        if (one_cluster) break;
        float z_j;
        bool bg_j;
        vec3 n_j;
        PICK(z_j, g_key, j)
        PICK(bg_j, g_bg, j)
        PICK(n_j, normals, j)
        bool joins = (((in_first | in_second) >> j) & 1) == 0
            && joins_second(z_j, bg_j, n_j, z_r, bg_r, n_r, z_s, bg_s, n_s);
        joined_second += joins ? 1 : 0;
    }
    float coverage = has_second ? float(second_size + joined_second) / float(NUM_SAMPLES) : 0.0;
    // From here on the seed is the reference; a pixel without a second
    // cluster writes sample 0's values, as a one-sample pixel does.
    r = has_second ? seed : 0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        z_r = i == r ? g_key[i] : z_r;
        bg_r = i == r ? g_bg[i] : bg_r;
        reference_depth = i == r ? g_raw_depth[i] : reference_depth;
        n_r = i == r ? normals[i] : n_r;
    }
    g_one = g_one || !has_second;
#endif

    // Sample 0 of everything, then samples 1.. in one loop that a group of
    // one-sample pixels leaves at the top of its first iteration.
    float depth_sum = 0.0;
    float depth_weight = 0.0;
    bool any_outside = false;
    ATTACHMENT_BEGINS
    for (int i = g_zero; i < NUM_SAMPLES; ++i) {
        float z_i;
        bool bg_i;
        float depth_i;
        PICK(z_i, g_key, i)
        PICK(bg_i, g_bg, i)
        PICK(depth_i, g_raw_depth, i)
#ifdef KEY_SAMPLER
        vec4 key_i;
        PICK(key_i, g_key_vals, i)
#endif
        float w = closeness(z_i, bg_i, i == r, z_r, bg_r);
#ifdef CLUSTER_NORMALS
        vec3 n_i;
        PICK(n_i, normals, i)
        w = same_normal(n_i, n_r, bg_i, bg_r) ? w : 0.0;
#endif
#ifdef SECOND_LAYER_OUTPUT
        w = ((in_first >> i) & 1) != 0 ? 0.0 : w;
#endif
        depth_sum += w * depth_i;
        depth_weight += w;
        any_outside = any_outside || w == 0.0;
        ATTACHMENT_STEPS
        // A group of one-sample pixels leaves here, after sample 0.
        if (g_one) break;
    }
    ATTACHMENT_ENDS

#ifdef WRITE_DEPTH
#ifdef BLEND_DEPTH
    gl_FragDepth = g_one ? reference_depth : depth_sum / depth_weight;
#else
    gl_FragDepth = reference_depth;
#endif
#endif
#ifdef SECOND_LAYER_OUTPUT
    // No second cluster: zeros and the background's depth, which host
    // lighting skips (what the retrofit clears the pixels it does not run on
    // to). The depth goes to a colour output: a shader writing gl_FragDepth
    // would lose the early stencil test that limits this pass to complex
    // pixels.
#ifdef BLEND_DEPTH
    float layer_depth = depth_sum / depth_weight;
#else
    float layer_depth = reference_depth;
#endif
    o_layer_depth = has_second ? layer_depth : u_clear_depth;
    ATTACHMENT_ZEROS
    o_coverage = coverage;
#endif
#ifdef COMPLEX_OUTPUT
    o_complex = g_one ? 0.0 : 1.0;
#endif
#ifdef OUTSIDE_OUTPUT
    o_outside = !g_one && any_outside ? 1.0 : 0.0;
#endif
#ifdef REFERENCE_OUTPUT
    o_reference = uint(g_one ? 0 : r);
#endif
}
