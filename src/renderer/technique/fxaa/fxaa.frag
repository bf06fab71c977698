// A luma-based edge smoothing post filter on the tonemapped (sRGB) image,
// the FXAA idea in this crate's own form:
//  1. Luma of the pixel and its 8 neighbours. Pixels whose local contrast is
//     small are left as they are.
//  2. Sobel gradients give the edge direction: the edge runs along the axis
//     in which luma changes less. Across it, the neighbour that differs more
//     from this pixel is the other side of the edge.
//  3. Walk along the seam between this pixel and that neighbour in both
//     directions until the seam's luma leaves the edge's; the nearer end
//     tells where on a stair step this pixel sits. Pixels near an end whose
//     step turns towards this pixel's row take up to half of the other side.
//  4. A sub-pixel term (the neighbourhood mean against the pixel) smooths
//     isolated pixels and thin lines the walk cannot see.
//  5. One bilinear tap, shifted across the edge by the larger amount.
// The input texture must be linearly filtered and clamped to the edge.

uniform sampler2D u_ldr;
uniform vec2 u_texel;          // 1 / size

out vec4 o_color;

#define SEARCH_STEPS 10
#define CONTRAST_MIN 0.04      // absolute luma contrast below which nothing is done
#define CONTRAST_REL 0.12      // ... and relative to the brightest neighbour
#define SUBPIXEL 0.6           // strength of the sub-pixel term

float luma(vec3 c) {
    return dot(c, vec3(0.299, 0.587, 0.114));
}

float luma_at(vec2 uv) {
    return luma(textureLod(u_ldr, uv, 0.0).rgb);
}

void main() {
    vec2 uv = gl_FragCoord.xy * u_texel;
    vec3 centre = textureLod(u_ldr, uv, 0.0).rgb;
    float c = luma(centre);
    float n = luma_at(uv + vec2(0.0, u_texel.y));
    float s = luma_at(uv - vec2(0.0, u_texel.y));
    float e = luma_at(uv + vec2(u_texel.x, 0.0));
    float w = luma_at(uv - vec2(u_texel.x, 0.0));
    float lo = min(c, min(min(n, s), min(e, w)));
    float hi = max(c, max(max(n, s), max(e, w)));
    float contrast = hi - lo;
    if (contrast < max(CONTRAST_MIN, CONTRAST_REL * hi)) {
        o_color = vec4(centre, 1.0);
        return;
    }
    float ne = luma_at(uv + u_texel);
    float sw = luma_at(uv - u_texel);
    float nw = luma_at(uv + vec2(-u_texel.x, u_texel.y));
    float se = luma_at(uv + vec2(u_texel.x, -u_texel.y));

    // Sobel: gx measures change from west to east, gy from south to north.
    float gx = (ne + 2.0 * e + se) - (nw + 2.0 * w + sw);
    float gy = (nw + 2.0 * n + ne) - (sw + 2.0 * s + se);
    bool runs_horizontally = abs(gy) >= abs(gx);

    vec2 across = runs_horizontally ? vec2(0.0, u_texel.y) : vec2(u_texel.x, 0.0);
    vec2 along = runs_horizontally ? vec2(u_texel.x, 0.0) : vec2(0.0, u_texel.y);
    float positive = runs_horizontally ? n : e;
    float negative = runs_horizontally ? s : w;
    float other = positive;
    if (abs(negative - c) > abs(positive - c)) {
        across = -across;
        other = negative;
    }

    // Walk the seam half a pixel across: a bilinear tap there averages the two rows.
    float seam = 0.5 * (c + other);
    float tolerance = 0.25 * abs(other - c);
    vec2 seam_uv = uv + 0.5 * across;
    float forward = float(SEARCH_STEPS + 1);
    float backward = float(SEARCH_STEPS + 1);
    float forward_luma = seam;
    float backward_luma = seam;
    for (int i = 1; i <= SEARCH_STEPS; ++i) {
        float l = luma_at(seam_uv + float(i) * along);
        if (abs(l - seam) > tolerance) {
            forward = float(i);
            forward_luma = l;
            break;
        }
    }
    for (int i = 1; i <= SEARCH_STEPS; ++i) {
        float l = luma_at(seam_uv - float(i) * along);
        if (abs(l - seam) > tolerance) {
            backward = float(i);
            backward_luma = l;
            break;
        }
    }
    float nearest = min(forward, backward);
    float end_luma = forward < backward ? forward_luma : backward_luma;
    // At the nearer end the step turns towards this pixel's row when the seam
    // there has become like the other side; only then does this pixel take
    // some of the other side (otherwise the neighbour row takes some of ours).
    bool turns_here = (end_luma - seam) * (other - c) > 0.0;
    float edge_amount = turns_here ? 0.5 - nearest / (forward + backward) : 0.0;
    edge_amount = max(edge_amount, 0.0);

    float mean = (2.0 * (n + s + e + w) + (ne + nw + se + sw)) / 12.0;
    float sub = clamp(abs(mean - c) / contrast, 0.0, 1.0);
    float sub_amount = SUBPIXEL * sub * sub * 0.5;

    float amount = max(edge_amount, sub_amount);
    o_color = vec4(textureLod(u_ldr, uv + amount * across, 0.0).rgb, 1.0);
}
