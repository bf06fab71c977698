// Depth-aware resolve of a multisampled G-buffer (DESIGN.md section 3).
// The CPU reference in src/resolve/cpu.rs implements the same math in f64;
// change both together.
//
// Defines set by src/resolve/mod.rs:
//   NUM_SAMPLES            real sample count N
//   SAMPLES_AS_LAYERS      read a sampler2DArray (one layer per sample) instead of sampler2DMS
//   NUM_ATTACHMENTS        colour attachments 0..7
//   ATTk_SAMPLER, ATTk_VEC sampler and value type of attachment k
//   ATTk_RULE              RULE_BLEND, RULE_BLEND_NORMAL, RULE_BLEND_HDR or RULE_SELECT
//   KEY_WORLD              the position attachment holds world-space positions:
//                          the key is -dot(u_view_row, (p, 1)), view space's -z
//   KEY_SAMPLER, KEY_INDEX the position attachment's sampler and number, when
//                          the key comes from it (its samples are fetched once)
//   METHOD                 METHOD_AVERAGE, METHOD_FRONT, METHOD_MEDIAN or METHOD_BACK
//   WINDOW_HARD            hard window (smooth otherwise)
//   FAST_PATH              uniform pixels copy sample 0
//   WRITE_DEPTH            write the resolved depth; BLEND_DEPTH blends it
//   COMPLEX_OUTPUT         also write 1.0 for pixels that took the slow path
//   REFERENCE_OUTPUT       also write the reference sample's index (0 for one-sample
//                          pixels): the host's stencil is copied from that sample
//   SELECT_REGION          selective AA: REGION_RECT or REGION_ELLIPSE (u_region)
//   SELECT_MAX_DEPTH       selective AA: pixels with no geometry sample nearer than
//                          u_max_depth take one sample
//   SELECT_FLAG_SAMPLER, SELECT_FLAG_COMPONENT
//                          selective AA: a pixel none of whose samples has this
//                          attachment component >= 0.5 takes one sample
//   PASS_CLASSIFY_TILES    the pass is the tile classification: one fragment per
//                          TILE_SIZE^2 tile writes 1.0 when any pixel of the tile
//                          needs the slow path (see src/resolve/tiles.rs)
//   PASS_ONE_SAMPLE        every pixel copies sample 0 of everything, nothing else is
//                          read; the slow tiles are drawn over it next

#define RULE_BLEND 0
#define RULE_BLEND_NORMAL 1
#define RULE_BLEND_HDR 2
#define RULE_SELECT 3
#define METHOD_AVERAGE 0
#define METHOD_FRONT 1
#define METHOD_MEDIAN 2
#define METHOD_BACK 3
#define REGION_RECT 1
#define REGION_ELLIPSE 2

#ifdef SAMPLES_AS_LAYERS
#define DEPTH_SAMPLER sampler2DArray
#define FETCH(s, p, i) texelFetch(s, ivec3(p, i), 0)
#else
#define DEPTH_SAMPLER sampler2DMS
#define FETCH(s, p, i) texelFetch(s, p, i)
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

#ifdef PASS_CLASSIFY_TILES
// Only the key attachment's sampler is needed; the others are declared
// without outputs (unused samplers cost nothing).
#define DECLARE_OUTPUTS 0
out float o_tile;
uniform ivec2 u_size;            // the resolve target's size in pixels
#else
#define DECLARE_OUTPUTS 1
#endif

#if NUM_ATTACHMENTS > 0
uniform ATT0_SAMPLER u_att0;
#if DECLARE_OUTPUTS
out ATT0_VEC o_att0;
#endif
#endif
#if NUM_ATTACHMENTS > 1
uniform ATT1_SAMPLER u_att1;
#if DECLARE_OUTPUTS
out ATT1_VEC o_att1;
#endif
#endif
#if NUM_ATTACHMENTS > 2
uniform ATT2_SAMPLER u_att2;
#if DECLARE_OUTPUTS
out ATT2_VEC o_att2;
#endif
#endif
#if NUM_ATTACHMENTS > 3
uniform ATT3_SAMPLER u_att3;
#if DECLARE_OUTPUTS
out ATT3_VEC o_att3;
#endif
#endif
#if NUM_ATTACHMENTS > 4
uniform ATT4_SAMPLER u_att4;
#if DECLARE_OUTPUTS
out ATT4_VEC o_att4;
#endif
#endif
#if NUM_ATTACHMENTS > 5
uniform ATT5_SAMPLER u_att5;
#if DECLARE_OUTPUTS
out ATT5_VEC o_att5;
#endif
#endif
#if NUM_ATTACHMENTS > 6
uniform ATT6_SAMPLER u_att6;
#if DECLARE_OUTPUTS
out ATT6_VEC o_att6;
#endif
#endif
#if NUM_ATTACHMENTS > 7
uniform ATT7_SAMPLER u_att7;
#if DECLARE_OUTPUTS
out ATT7_VEC o_att7;
#endif
#endif
#if defined(COMPLEX_OUTPUT) && DECLARE_OUTPUTS
out float o_complex;
#endif
#if defined(REFERENCE_OUTPUT) && DECLARE_OUTPUTS
out uint o_reference;
#endif

// Per-pixel state shared by the attachment blocks below.
float g_key[NUM_SAMPLES];      // depth key z_i (meaningless where g_bg)
bool g_bg[NUM_SAMPLES];        // background: clear depth, or a non-finite key
float g_sort[NUM_SAMPLES];     // z_i, or +inf for background: the order of key_less
float g_raw_depth[NUM_SAMPLES];
float g_w[NUM_SAMPLES];        // closeness weights, g_w[ref] == 1
vec4 g_vals[NUM_SAMPLES];      // scratch: one attachment's samples
#ifdef KEY_SAMPLER
vec4 g_key_vals[NUM_SAMPLES];  // the key attachment's samples, fetched once
#endif

bool is_finite(vec4 x) {
    return !any(isnan(x)) && !any(isinf(x));
}

// Fill g_raw_depth, g_key, g_bg and g_sort (and the key attachment's samples) for pixel p.
void load_keys(ivec2 p) {
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
}

// One float attachment's samples into g_vals.
void load_values(DEPTH_SAMPLER s, ivec2 p) {
    for (int i = 0; i < NUM_SAMPLES; ++i) g_vals[i] = vec4(FETCH(s, p, i));
}

// Strict order by (z, index) with background at +infinity. Geometry keys are
// finite (a non-finite key is background), so comparing g_sort is that order;
// written without branches, which a SIMD rasteriser would run both sides of.
bool key_less(int i, int j) {
    return g_sort[i] < g_sort[j] || (g_sort[i] == g_sort[j] && i < j);
}

// The code below is written with selects rather than branches and with no
// array indexed by a run-time value (those become select chains anyway): a
// SIMD rasteriser such as llvmpipe runs both sides of every branch that its
// lanes disagree on, and masks every store made inside one.

int reference_sample() {
    int r = 0;
#if METHOD == METHOD_FRONT
    // Nearest; the sweep only replaces r by a higher index, so a tie keeps r.
    float best = g_sort[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        bool nearer = g_sort[i] < best;
        r = nearer ? i : r;
        best = nearer ? g_sort[i] : best;
    }
#elif METHOD == METHOD_BACK
    // Farthest; among equal depths the lower index.
    float best = g_sort[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        bool farther = g_sort[i] > best;
        r = farther ? i : r;
        best = farther ? g_sort[i] : best;
    }
#else
    // Median (also the average's reference): the sample whose rank under
    // key_less is N/2. Ranks are counted, not sorted, so every sample's own
    // depth decides its place.
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        int rank = 0;
        for (int j = 0; j < NUM_SAMPLES; ++j) rank += key_less(j, i) ? 1 : 0;
        r = rank == NUM_SAMPLES / 2 ? i : r;
    }
#endif
    return r;
}

// Closeness of sample i to the reference r, whose key and background flag
// are z_r and bg_r.
float closeness(int i, int r, float z_r, bool bg_r) {
#if METHOD == METHOD_AVERAGE
    return 1.0;
#else
    float d = abs(g_key[i] - z_r);
    float m = min(g_key[i], z_r) * u_footprint;
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
    w = g_bg[i] || bg_r ? (g_bg[i] && bg_r ? 1.0 : 0.0) : w;
    return i == r ? 1.0 : w;
#endif
}

float max3(vec3 v) {
    return max(v.x, max(v.y, v.z));
}

// g_vals[r] without indexing by a run-time value.
vec4 value_at(int r) {
    vec4 v = g_vals[0];
    for (int i = 1; i < NUM_SAMPLES; ++i) v = i == r ? g_vals[i] : v;
    return v;
}

// Weighted mean of g_vals over finite samples; the reference's value when none weigh.
vec4 blend(int r) {
    vec4 sum = vec4(0.0);
    float weight = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        bool used = g_w[i] > 0.0 && is_finite(g_vals[i]);
        sum += used ? g_w[i] * g_vals[i] : vec4(0.0);
        weight += used ? g_w[i] : 0.0;
    }
    return weight > 0.0 ? sum / weight : value_at(r);
}

// The weighted sum of normals, normalised; w blends as blend() does (one loop for both).
vec4 blend_normal(int r) {
    vec4 sum = vec4(0.0);
    float weight = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        bool used = g_w[i] > 0.0 && is_finite(g_vals[i]);
        sum += used ? g_w[i] * g_vals[i] : vec4(0.0);
        weight += used ? g_w[i] : 0.0;
    }
    vec4 reference = value_at(r);
    float len = length(sum.xyz);
    float w = weight > 0.0 ? sum.w / weight : reference.w;
    return vec4(len >= 1e-6 ? sum.xyz / len : reference.xyz, w);
}

// Blend in the tonemapped domain T(x) = x / (1 + max3(x)) so one bright sample
// cannot swamp its neighbours, and map back with T^-1(y) = y / (1 - max3(y)).
// 1 - max3(y) is accumulated directly as min over channels of the blended
// (1 + m - x) / (1 + m): the same value, without the cancellation that costs
// f32 three digits near 65504. The result is kept inside the contributing
// samples' range.
vec4 blend_hdr(int r) {
    vec3 sum = vec3(0.0);
    vec3 complement = vec3(0.0);
    float alpha = 0.0;
    float weight = 0.0;
    vec3 lo = vec3(u_infinity);
    vec3 hi = vec3(-u_infinity);
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        bool used = g_w[i] > 0.0 && is_finite(g_vals[i]);
        vec3 x = g_vals[i].rgb;
        float m = max(max3(x), 0.0);
        float w = used ? g_w[i] : 0.0;
        sum += used ? w * (x / (1.0 + m)) : vec3(0.0);
        complement += used ? w * ((1.0 + m - x) / (1.0 + m)) : vec3(0.0);
        alpha += used ? w * g_vals[i].a : 0.0;
        weight += w;
        lo = used ? min(lo, x) : lo;
        hi = used ? max(hi, x) : hi;
    }
    float denominator = min(min(complement.x, complement.y), min(complement.z, weight));
    vec3 x = sum / max(denominator, 1e-30);
    return weight > 0.0 ? vec4(clamp(x, lo, hi), alpha / weight) : value_at(r);
}

vec4 resolve_rule(int rule, int r) {
    if (rule == RULE_BLEND_NORMAL) return blend_normal(r);
    if (rule == RULE_BLEND_HDR) return blend_hdr(r);
    return blend(r);
}

// Uniform pixel: every sample is background, or every sample is geometry
// with the same key.
bool keys_uniform() {
    bool same = true;
    for (int i = 1; i < NUM_SAMPLES; ++i)
        if (g_bg[i] != g_bg[0] || (!g_bg[0] && g_key[i] != g_key[0])) same = false;
    return same;
}

// Selective anti-aliasing: the pixel lies outside what should be anti-aliased.
bool outside_selection(ivec2 p) {
    bool outside = false;
#if defined(SELECT_REGION)
    vec2 c = vec2(p) + 0.5;
#if SELECT_REGION == REGION_RECT
    outside = any(lessThan(c, u_region.xy)) || any(greaterThanEqual(c, u_region.zw));
#else
    vec2 d = (c - u_region.xy) * u_region.zw;
    outside = dot(d, d) > 1.0;
#endif
#endif
#ifdef SELECT_MAX_DEPTH
    bool near = false;
    for (int i = 0; i < NUM_SAMPLES; ++i)
        if (!g_bg[i] && g_key[i] <= u_max_depth) near = true;
    outside = outside || !near;
#endif
#ifdef SELECT_FLAG_SAMPLER
    bool wanted = false;
    for (int i = 0; i < NUM_SAMPLES; ++i)
        if (FETCH(SELECT_FLAG_SAMPLER, p, i).SELECT_FLAG_COMPONENT >= 0.5) wanted = true;
    outside = outside || !wanted;
#endif
    return outside;
}

// The pixel takes one sample (sample 0 of everything): it is uniform (with
// the fast path), or outside the selection. Needs load_keys(p) first.
bool takes_one_sample(ivec2 p) {
    bool one = outside_selection(p);
#ifdef FAST_PATH
    one = one || keys_uniform();
#endif
    return one;
}

#ifdef PASS_CLASSIFY_TILES

void main() {
    ivec2 origin = ivec2(gl_FragCoord.xy) * TILE_SIZE;
    ivec2 end = min(origin + TILE_SIZE, u_size);
    bool slow = false;
    // Stop at the first slow pixel: a loop ends once every lane has left it.
    for (int y = origin.y; y < end.y && !slow; ++y) {
        for (int x = origin.x; x < end.x && !slow; ++x) {
            load_keys(ivec2(x, y));
            if (!takes_one_sample(ivec2(x, y))) slow = true;
        }
    }
    o_tile = slow ? 1.0 : 0.0;
}

#else

#ifdef PASS_ONE_SAMPLE
// Every pixel copies sample 0 and reads nothing else (slow tiles are drawn over it).
#define RESOLVE_SELECT(S, O) O = FETCH(S, p, 0);
#define RESOLVE_BLEND(S, O, RULE) O = FETCH(S, p, 0);
#define RESOLVE_KEY(S, O, RULE) O = FETCH(S, p, 0);
#else
#define FETCH_ALL(S) load_values(S, p);
#define RESOLVE_SELECT(S, O) O = FETCH(S, p, one_sample ? 0 : r);
#define RESOLVE_BLEND(S, O, RULE) if (one_sample) { O = FETCH(S, p, 0); } else { FETCH_ALL(S) O = resolve_rule(RULE, r); }
#define RESOLVE_KEY(S, O, RULE) for (int i = 0; i < NUM_SAMPLES; ++i) g_vals[i] = g_key_vals[i]; if (one_sample) { O = g_key_vals[0]; } else if (RULE == RULE_SELECT) { O = value_at(r); } else { O = resolve_rule(RULE, r); }
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);

#ifdef PASS_ONE_SAMPLE
    const bool one_sample = true;
#else
    load_keys(p);
    bool one_sample = takes_one_sample(p);
    int r = 0;
    float reference_depth = g_raw_depth[0];
    if (!one_sample) {
        r = reference_sample();
        float z_r = g_key[0];
        bool bg_r = g_bg[0];
        for (int i = 1; i < NUM_SAMPLES; ++i) {
            z_r = i == r ? g_key[i] : z_r;
            bg_r = i == r ? g_bg[i] : bg_r;
            reference_depth = i == r ? g_raw_depth[i] : reference_depth;
        }
        for (int i = 0; i < NUM_SAMPLES; ++i) g_w[i] = closeness(i, r, z_r, bg_r);
    }
#endif

#if NUM_ATTACHMENTS > 0
#if defined(KEY_INDEX) && KEY_INDEX == 0
    RESOLVE_KEY(u_att0, o_att0, ATT0_RULE)
#elif ATT0_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att0, o_att0)
#else
    RESOLVE_BLEND(u_att0, o_att0, ATT0_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 1
#if defined(KEY_INDEX) && KEY_INDEX == 1
    RESOLVE_KEY(u_att1, o_att1, ATT1_RULE)
#elif ATT1_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att1, o_att1)
#else
    RESOLVE_BLEND(u_att1, o_att1, ATT1_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 2
#if defined(KEY_INDEX) && KEY_INDEX == 2
    RESOLVE_KEY(u_att2, o_att2, ATT2_RULE)
#elif ATT2_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att2, o_att2)
#else
    RESOLVE_BLEND(u_att2, o_att2, ATT2_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 3
#if defined(KEY_INDEX) && KEY_INDEX == 3
    RESOLVE_KEY(u_att3, o_att3, ATT3_RULE)
#elif ATT3_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att3, o_att3)
#else
    RESOLVE_BLEND(u_att3, o_att3, ATT3_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 4
#if defined(KEY_INDEX) && KEY_INDEX == 4
    RESOLVE_KEY(u_att4, o_att4, ATT4_RULE)
#elif ATT4_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att4, o_att4)
#else
    RESOLVE_BLEND(u_att4, o_att4, ATT4_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 5
#if defined(KEY_INDEX) && KEY_INDEX == 5
    RESOLVE_KEY(u_att5, o_att5, ATT5_RULE)
#elif ATT5_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att5, o_att5)
#else
    RESOLVE_BLEND(u_att5, o_att5, ATT5_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 6
#if defined(KEY_INDEX) && KEY_INDEX == 6
    RESOLVE_KEY(u_att6, o_att6, ATT6_RULE)
#elif ATT6_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att6, o_att6)
#else
    RESOLVE_BLEND(u_att6, o_att6, ATT6_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 7
#if defined(KEY_INDEX) && KEY_INDEX == 7
    RESOLVE_KEY(u_att7, o_att7, ATT7_RULE)
#elif ATT7_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att7, o_att7)
#else
    RESOLVE_BLEND(u_att7, o_att7, ATT7_RULE)
#endif
#endif

#ifdef WRITE_DEPTH
#ifdef PASS_ONE_SAMPLE
    gl_FragDepth = FETCH(u_depth, p, 0).r;
#else
    float depth_out = reference_depth;
#ifdef BLEND_DEPTH
    if (!one_sample) {
        float sum = 0.0;
        float weight = 0.0;
        for (int i = 0; i < NUM_SAMPLES; ++i) {
            sum += g_w[i] * g_raw_depth[i];
            weight += g_w[i];
        }
        depth_out = sum / weight;
    }
#endif
    gl_FragDepth = depth_out;
#endif
#endif
#ifdef COMPLEX_OUTPUT
    o_complex = one_sample ? 0.0 : 1.0;
#endif
#ifdef REFERENCE_OUTPUT
#ifdef PASS_ONE_SAMPLE
    o_reference = 0u;
#else
    o_reference = uint(one_sample ? 0 : r);
#endif
#endif
}

#endif
