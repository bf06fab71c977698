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
//   KEY_SAMPLER, KEY_INDEX the position attachment's sampler and number, when
//                          the key comes from it (its samples are fetched once)
//   METHOD                 METHOD_AVERAGE, METHOD_FRONT, METHOD_MEDIAN or METHOD_BACK
//   WINDOW_HARD            hard window (smooth otherwise)
//   FAST_PATH              uniform pixels copy sample 0
//   WRITE_DEPTH            write the resolved depth; BLEND_DEPTH blends it
//   COMPLEX_OUTPUT         also write 1.0 for pixels that took the slow path

#define RULE_BLEND 0
#define RULE_BLEND_NORMAL 1
#define RULE_BLEND_HDR 2
#define RULE_SELECT 3
#define METHOD_AVERAGE 0
#define METHOD_FRONT 1
#define METHOD_MEDIAN 2
#define METHOD_BACK 3

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

#if NUM_ATTACHMENTS > 0
uniform ATT0_SAMPLER u_att0;
out ATT0_VEC o_att0;
#endif
#if NUM_ATTACHMENTS > 1
uniform ATT1_SAMPLER u_att1;
out ATT1_VEC o_att1;
#endif
#if NUM_ATTACHMENTS > 2
uniform ATT2_SAMPLER u_att2;
out ATT2_VEC o_att2;
#endif
#if NUM_ATTACHMENTS > 3
uniform ATT3_SAMPLER u_att3;
out ATT3_VEC o_att3;
#endif
#if NUM_ATTACHMENTS > 4
uniform ATT4_SAMPLER u_att4;
out ATT4_VEC o_att4;
#endif
#if NUM_ATTACHMENTS > 5
uniform ATT5_SAMPLER u_att5;
out ATT5_VEC o_att5;
#endif
#if NUM_ATTACHMENTS > 6
uniform ATT6_SAMPLER u_att6;
out ATT6_VEC o_att6;
#endif
#if NUM_ATTACHMENTS > 7
uniform ATT7_SAMPLER u_att7;
out ATT7_VEC o_att7;
#endif
#ifdef COMPLEX_OUTPUT
out float o_complex;
#endif

// Per-pixel state shared by the attachment blocks below.
float g_key[NUM_SAMPLES];      // depth key z_i (meaningless where g_bg)
bool g_bg[NUM_SAMPLES];        // background: clear depth, or a non-finite key
float g_raw_depth[NUM_SAMPLES];
float g_w[NUM_SAMPLES];        // closeness weights, g_w[ref] == 1
vec4 g_vals[NUM_SAMPLES];      // scratch: one attachment's samples
#ifdef KEY_SAMPLER
vec4 g_key_vals[NUM_SAMPLES];  // the key attachment's samples, fetched once
#endif

bool is_finite(vec4 x) {
    return !any(isnan(x)) && !any(isinf(x));
}

// Strict order by (z, index) with background at +infinity.
bool key_less(int i, int j) {
    if (g_bg[i] != g_bg[j]) return g_bg[j];
    if (!g_bg[i] && g_key[i] != g_key[j]) return g_key[i] < g_key[j];
    return i < j;
}

int reference_sample() {
    int r = 0;
#if METHOD == METHOD_FRONT
    for (int i = 1; i < NUM_SAMPLES; ++i)
        if (key_less(i, r)) r = i;
#elif METHOD == METHOD_BACK
    // Farthest; among equal depths the lower index, so never key_less reversed.
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        bool farther = !g_bg[r] && (g_bg[i] || g_key[i] > g_key[r]);
        if (farther) r = i;
    }
#else
    // Median (also the average's reference): the sample whose rank under
    // key_less is N/2. Ranks are counted, not sorted, so every sample's own
    // depth decides its place.
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        int rank = 0;
        for (int j = 0; j < NUM_SAMPLES; ++j)
            if (key_less(j, i)) ++rank;
        if (rank == NUM_SAMPLES / 2) r = i;
    }
#endif
    return r;
}

float closeness(int i, int r) {
    if (i == r) return 1.0;
#if METHOD == METHOD_AVERAGE
    return 1.0;
#else
    if (g_bg[r]) return g_bg[i] ? 1.0 : 0.0;
    if (g_bg[i]) return 0.0;
    float d = abs(g_key[i] - g_key[r]);
    float m = min(g_key[i], g_key[r]) * u_footprint;
#ifdef WINDOW_HARD
    return d <= u_c * m ? 1.0 : 0.0;
#else
    if (d <= u_c_in * m) return 1.0;
    if (d >= u_c * m) return 0.0;
    // 1 - smoothstep(t) == smoothstep(1 - t): measure from the outer edge so a
    // weight near 0 is not the difference of two numbers near 1.
    float u = (u_c * m - d) / ((u_c - u_c_in) * m);
    return u * u * (3.0 - 2.0 * u);
#endif
#endif
}

float max3(vec3 v) {
    return max(v.x, max(v.y, v.z));
}

// Weighted mean of g_vals over finite samples; the reference's value when none weigh.
vec4 blend(int r) {
    vec4 sum = vec4(0.0);
    float weight = 0.0;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        if (g_w[i] > 0.0 && is_finite(g_vals[i])) {
            sum += g_w[i] * g_vals[i];
            weight += g_w[i];
        }
    }
    return weight > 0.0 ? sum / weight : g_vals[r];
}

vec4 blend_normal(int r) {
    vec4 mean = blend(r);
    vec3 n = vec3(0.0);
    for (int i = 0; i < NUM_SAMPLES; ++i)
        if (g_w[i] > 0.0 && is_finite(g_vals[i])) n += g_w[i] * g_vals[i].xyz;
    float len = length(n);
    return vec4(len >= 1e-6 ? n / len : g_vals[r].xyz, mean.w);
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
    vec3 lo = vec3(0.0);
    vec3 hi = vec3(0.0);
    bool first = true;
    for (int i = 0; i < NUM_SAMPLES; ++i) {
        if (g_w[i] > 0.0 && is_finite(g_vals[i])) {
            vec3 x = g_vals[i].rgb;
            float m = max(max3(x), 0.0);
            sum += g_w[i] * (x / (1.0 + m));
            complement += g_w[i] * ((1.0 + m - x) / (1.0 + m));
            alpha += g_w[i] * g_vals[i].a;
            weight += g_w[i];
            lo = first ? x : min(lo, x);
            hi = first ? x : max(hi, x);
            first = false;
        }
    }
    if (weight <= 0.0) return g_vals[r];
    float denominator = min(min(complement.x, complement.y), min(complement.z, weight));
    vec3 x = sum / max(denominator, 1e-30);
    return vec4(clamp(x, lo, hi), alpha / weight);
}

vec4 resolve_rule(int rule, int r) {
    if (rule == RULE_BLEND_NORMAL) return blend_normal(r);
    if (rule == RULE_BLEND_HDR) return blend_hdr(r);
    return blend(r);
}

#define FETCH_ALL(S) for (int i = 0; i < NUM_SAMPLES; ++i) g_vals[i] = vec4(FETCH(S, p, i));
#define RESOLVE_SELECT(S, O) O = FETCH(S, p, uniform_pixel ? 0 : r);
#define RESOLVE_BLEND(S, O, RULE) if (uniform_pixel) { O = FETCH(S, p, 0); } else { FETCH_ALL(S) O = resolve_rule(RULE, r); }
#define RESOLVE_KEY(O, RULE) if (uniform_pixel) { O = g_key_vals[0]; } else if (RULE == RULE_SELECT) { O = g_key_vals[r]; } else { for (int i = 0; i < NUM_SAMPLES; ++i) g_vals[i] = g_key_vals[i]; O = resolve_rule(RULE, r); }

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);

    for (int i = 0; i < NUM_SAMPLES; ++i) {
        float depth = FETCH(u_depth, p, i).r;
        g_raw_depth[i] = depth;
#ifdef KEY_SAMPLER
        g_key_vals[i] = FETCH(KEY_SAMPLER, p, i);
        float z = -g_key_vals[i].z;
#else
        float z = u_projection.y / (depth * u_depth_to_ndc.x + u_depth_to_ndc.y + u_projection.x);
#endif
        g_bg[i] = depth == u_clear_depth || isnan(z) || isinf(z);
        g_key[i] = z;
    }

    // Uniform pixel: every sample is background, or every sample is geometry
    // with the same key. Then all attachments take sample 0.
    bool uniform_pixel = false;
#ifdef FAST_PATH
    uniform_pixel = true;
    for (int i = 1; i < NUM_SAMPLES; ++i)
        if (g_bg[i] != g_bg[0] || (!g_bg[0] && g_key[i] != g_key[0])) uniform_pixel = false;
#endif

    int r = 0;
    if (!uniform_pixel) {
        r = reference_sample();
        for (int i = 0; i < NUM_SAMPLES; ++i) g_w[i] = closeness(i, r);
    }

#if NUM_ATTACHMENTS > 0
#if defined(KEY_INDEX) && KEY_INDEX == 0
    RESOLVE_KEY(o_att0, ATT0_RULE)
#elif ATT0_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att0, o_att0)
#else
    RESOLVE_BLEND(u_att0, o_att0, ATT0_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 1
#if defined(KEY_INDEX) && KEY_INDEX == 1
    RESOLVE_KEY(o_att1, ATT1_RULE)
#elif ATT1_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att1, o_att1)
#else
    RESOLVE_BLEND(u_att1, o_att1, ATT1_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 2
#if defined(KEY_INDEX) && KEY_INDEX == 2
    RESOLVE_KEY(o_att2, ATT2_RULE)
#elif ATT2_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att2, o_att2)
#else
    RESOLVE_BLEND(u_att2, o_att2, ATT2_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 3
#if defined(KEY_INDEX) && KEY_INDEX == 3
    RESOLVE_KEY(o_att3, ATT3_RULE)
#elif ATT3_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att3, o_att3)
#else
    RESOLVE_BLEND(u_att3, o_att3, ATT3_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 4
#if defined(KEY_INDEX) && KEY_INDEX == 4
    RESOLVE_KEY(o_att4, ATT4_RULE)
#elif ATT4_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att4, o_att4)
#else
    RESOLVE_BLEND(u_att4, o_att4, ATT4_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 5
#if defined(KEY_INDEX) && KEY_INDEX == 5
    RESOLVE_KEY(o_att5, ATT5_RULE)
#elif ATT5_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att5, o_att5)
#else
    RESOLVE_BLEND(u_att5, o_att5, ATT5_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 6
#if defined(KEY_INDEX) && KEY_INDEX == 6
    RESOLVE_KEY(o_att6, ATT6_RULE)
#elif ATT6_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att6, o_att6)
#else
    RESOLVE_BLEND(u_att6, o_att6, ATT6_RULE)
#endif
#endif
#if NUM_ATTACHMENTS > 7
#if defined(KEY_INDEX) && KEY_INDEX == 7
    RESOLVE_KEY(o_att7, ATT7_RULE)
#elif ATT7_RULE == RULE_SELECT
    RESOLVE_SELECT(u_att7, o_att7)
#else
    RESOLVE_BLEND(u_att7, o_att7, ATT7_RULE)
#endif
#endif

#ifdef WRITE_DEPTH
    float depth_out = g_raw_depth[uniform_pixel ? 0 : r];
#ifdef BLEND_DEPTH
    if (!uniform_pixel) {
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
#ifdef COMPLEX_OUTPUT
    o_complex = uniform_pixel ? 0.0 : 1.0;
#endif
}
