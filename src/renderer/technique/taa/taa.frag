// The resolve of method `taa`, temporal anti-aliasing as engines ship it,
// in this crate's own form. Every frame is rendered with its projection
// shifted by a sub-pixel offset (technique/taa.rs picks it from the
// Halton (2, 3) sequence); this pass then accumulates the frames:
//  1. Reprojection: the pixel's centre (where the unjittered frame would
//     sample it) and its depth give a point in this frame's NDC, which
//     u_reproject takes to the previous frame's clip space; divided by w,
//     that is where the surface was in the history.
//  2. The history there, Catmull-Rom filtered from 4x4 texels (a bilinear
//     tap would blur the history a little more on every frame the camera
//     moves; at a texel centre the filter returns the texel itself).
//  3. Variance clipping of every pixel while the camera moves: in YCoCg,
//     the box of mean +- u_gamma standard deviations of this frame's 3x3
//     neighbourhood, within its min-max box; the history is pulled towards
//     the box's centre until it lies inside it, so a colour this frame
//     does not show near the pixel cannot linger. That holds where the
//     pixel itself barely moves too: a far background or the sky a thin
//     bar has just left holds the bar in its history, a disocclusion no
//     shipped TAA keeps. While the camera is still nothing is uncovered.
//  4. A blend by confidence: the history's alpha counts the frames it
//     accumulated; this frame weighs 1 / count (a running mean), but at
//     least u_alpha while the camera moves and u_alpha_still while it does
//     not, so a still camera converges on many phases while a moving one
//     keeps up.
//  The motion comes from the nearest surface of the 3x3 neighbourhood
//  (velocity dilation): an edge pixel whose own sample is the background
//  reprojects with the object in front of it, as the history there does.
//  Where the reprojected point leaves the screen or lies behind the
//  previous camera, and on the first frame, the history is reset to this
//  frame.
// Colours are linear display values: the tonemapped frame, after the curve
// and before the sRGB encoding (u_current is an sRGB texture, so fetches
// decode), the way the supersampled reference and the per-sample lighting
// average their samples. o_color is the sRGB-encoded result for the LDR
// image, o_history the same result in linear RGBA16F for the next frame.
// With TAA_REPROJECTED defined the pass writes the reprojected history
// alone (step 2, no clipping, sRGB-encoded; alpha 1 where it was found,
// 0 where it was reset), to check the reprojection.

uniform sampler2D u_current;
uniform sampler2D u_history;
uniform sampler2D u_depth;
uniform mat4 u_reproject;      // this frame's unjittered NDC -> the previous frame's clip space
uniform int u_has_history;     // 0 on the first frame after a reset
uniform int u_zero_to_one;     // 1: NDC z is the depth value (reversed-Z); 0: z = 2 depth - 1
uniform float u_alpha;         // weight of this frame
uniform float u_gamma;         // half-size of the clip box in standard deviations
uniform float u_alpha_still;   // the least weight of this frame while the camera is still
uniform int u_camera_still;    // 1: the camera has not moved since the last frame

out vec4 o_color;
#ifndef TAA_REPROJECTED
out vec4 o_history;
#endif

vec3 to_ycocg(vec3 c) {
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b,
                0.5 * c.r - 0.5 * c.b,
                -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}

vec3 from_ycocg(vec3 c) {
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

vec3 current_at(ivec2 p, ivec2 size) {
    return texelFetch(u_current, clamp(p, ivec2(0), size - 1), 0).rgb;
}

// The history at `pos` (in pixels, texel centres at k + 0.5), Catmull-Rom
// in both axes over the 4x4 texels around it, the edges clamped.
vec3 history_at(vec2 pos, ivec2 size) {
    vec2 t = pos - 0.5;
    vec2 base = floor(t);
    vec2 f = t - base;
    vec2 w[4];
    w[0] = f * (-0.5 + f * (1.0 - 0.5 * f));
    w[1] = 1.0 + f * f * (-2.5 + 1.5 * f);
    w[2] = f * (0.5 + f * (2.0 - 1.5 * f));
    w[3] = f * f * (-0.5 + 0.5 * f);
    ivec2 origin = ivec2(base) - 1;
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
            ivec2 q = clamp(origin + ivec2(i, j), ivec2(0), size - 1);
            sum += w[i].x * w[j].y * texelFetch(u_history, q, 0).rgb;
        }
    }
    // The filter's negative lobes can undershoot next to a bright edge.
    return max(sum, vec3(0.0));
}

// `h` pulled along the line towards the box's centre until it is inside.
vec3 clip_to_box(vec3 h, vec3 lo, vec3 hi) {
    vec3 centre = 0.5 * (lo + hi);
    vec3 half_size = max(0.5 * (hi - lo), vec3(1e-5));
    vec3 d = h - centre;
    vec3 reach = abs(d) / half_size;
    float outside = max(reach.x, max(reach.y, reach.z));
    return outside > 1.0 ? centre + d / outside : h;
}

// This frame's unjittered NDC z of pixel `q`'s depth.
float ndc_z(ivec2 q) {
    float depth = texelFetch(u_depth, q, 0).r;
    return u_zero_to_one != 0 ? depth : 2.0 * depth - 1.0;
}

void main() {
    ivec2 size = textureSize(u_current, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 current = current_at(p, size);

    // 1. Where this pixel's surface was in the previous frame, moved as
    // the nearest surface of its neighbourhood moved.
    ivec2 nearest = p;
    float nearest_z = ndc_z(p);
    for (int j = -1; j <= 1; ++j) {
        for (int i = -1; i <= 1; ++i) {
            ivec2 q = clamp(p + ivec2(i, j), ivec2(0), size - 1);
            float z = ndc_z(q);
            // Reversed-Z (zero-to-one) keeps the nearest at the largest value.
            bool nearer = u_zero_to_one != 0 ? z > nearest_z : z < nearest_z;
            nearest = nearer ? q : nearest;
            nearest_z = nearer ? z : nearest_z;
        }
    }
    vec2 nearest_ndc = (vec2(nearest) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 previous = u_reproject * vec4(nearest_ndc, nearest_z, 1.0);
    bool found = u_has_history != 0 && previous.w > 0.0;
    vec2 previous_px = vec2(-1.0);
    vec2 motion = vec2(0.0);
    if (found) {
        motion = (previous.xy / previous.w * 0.5 + 0.5) * vec2(size) - (vec2(nearest) + 0.5);
        previous_px = vec2(p) + 0.5 + motion;
        found = all(greaterThanEqual(previous_px, vec2(0.0)))
            && all(lessThanEqual(previous_px, vec2(size)));
    }

#ifdef TAA_REPROJECTED
    vec3 shown = found ? history_at(previous_px, size) : vec3(0.0);
    o_color = vec4(srgb_encode(clamp(shown, 0.0, 1.0)), found ? 1.0 : 0.0);
#else
    vec3 result = current;
    float count = 1.0;
    if (found) {
        // 2. The history, and how many frames it holds.
        vec3 history = to_ycocg(history_at(previous_px, size));
        float held = texelFetch(u_history, clamp(ivec2(previous_px), ivec2(0), size - 1), 0).a;
        // 3. The neighbourhood's box in YCoCg.
        vec3 m1 = vec3(0.0);
        vec3 m2 = vec3(0.0);
        vec3 lo = vec3(1e9);
        vec3 hi = vec3(-1e9);
        for (int j = -1; j <= 1; ++j) {
            for (int i = -1; i <= 1; ++i) {
                vec3 c = to_ycocg(current_at(p + ivec2(i, j), size));
                m1 += c;
                m2 += c * c;
                lo = min(lo, c);
                hi = max(hi, c);
            }
        }
        m1 /= 9.0;
        vec3 sigma = sqrt(max(m2 / 9.0 - m1 * m1, vec3(0.0)));
        // While the camera moves, every pixel is clipped, whatever its own
        // motion (the sky and a far wall barely move, yet a bar passing in
        // front uncovers them). While it is still, the scene (static here)
        // uncovers nothing, and a clip would only pull the mean of the
        // jitter's phases towards the one phase this frame shows.
        bool still = u_camera_still != 0;
        vec3 box_lo = max(m1 - u_gamma * sigma, lo);
        vec3 box_hi = min(m1 + u_gamma * sigma, hi);
        history = from_ycocg(still ? history : clip_to_box(history, box_lo, box_hi));
        // 4. The blend: a running mean, floored by the pixel's motion.
        count = clamp(held, 1.0, 1024.0) + 1.0;
        float least = still ? u_alpha_still : u_alpha;
        float weight = max(1.0 / count, least);
        result = mix(max(history, vec3(0.0)), current, weight);
    }
    o_history = vec4(result, count);
    o_color = vec4(srgb_encode(clamp(result, 0.0, 1.0)), 1.0);
#endif
}
