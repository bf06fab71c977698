// The lighting pass of method `sparse`: every block of a pixel's list is lit
// once, with lighting.frag's shade_surface() and every light, and weighted
// by the number of samples it is visible in; the samples no block covers
// show the background. Compiled after lighting.frag (with
// LIGHTING_FUNCTIONS_ONLY and LIGHT_BLOCK), tonemap.frag (with
// TONEMAP_FUNCTIONS_ONLY) and sparse.frag, with
// GL_ARB_shader_storage_buffer_object, _shading_language_packing and
// _shading_language_420pack.
//
// The average is taken as lighting_per_sample.frag takes it: after the
// tonemap curve, then mapped back to HDR (u_tonemapped_average = 1), so
// the result is per-sample lighting's, computed once per distinct fragment
// instead of once per sample; a pixel whose samples all show one surface
// keeps its radiance exactly. With more lights than one block holds the
// pass draws once per block and adds, and the average is linear.
//
// A pixel flagged SPARSE_OVERFLOW or SPARSE_SINGLE, or outside the
// anti-aliased region, shows its sample 0: the first block, or the
// background when sample 0 has no surface.

layout(std430, binding = 0) readonly buffer SparseHeads {
    uint heads[];
};
layout(std430, binding = 1) readonly buffer SparseFirstBlocks {
    uvec4 first_blocks[];
};
layout(std430, binding = 2) readonly buffer SparsePoolBlocks {
    uvec4 pool_blocks[];
};

uniform sampler2D u_background;    // the background, drawn single-sampled
uniform uint u_pool_capacity;
uniform int u_samples;             // the pre-pass's real sample count (<= SPARSE_MAX_SAMPLES)
uniform int u_tonemapped_average;  // 1: average after the tonemap curve
uniform vec2 u_viewport;           // width, height in pixels
uniform vec4 u_ndc_to_view;        // 1 / P[0][0], 1 / P[1][1], P[2][0], P[2][1]

out vec4 o_color;

vec3 octahedral_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        vec2 signs = vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
        n.xy = (1.0 - abs(n.yx)) * signs;
    }
    return normalize(n);
}

// The radiance of one block, for the pixel whose centre is at `ndc`.
vec3 shade_block(uvec4 a, uvec4 b, vec2 ndc) {
    vec2 rg = unpackHalf2x16(a.x);
    vec2 b_gloss = unpackHalf2x16(a.y);
    vec4 specular = unpackUnorm4x8(a.z);
    vec3 normal = octahedral_decode(unpackSnorm2x16(a.w));
    float z = uintBitsToFloat(b.x);
    // The fragment's interpolated view position at the pixel centre lies on
    // the centre's ray: clip = P * p with clip.w = -z.
    vec2 xy = -z * (ndc + u_ndc_to_view.zw) * u_ndc_to_view.xy;
    vec3 emissive = vec3(unpackHalf2x16(b.y), unpackHalf2x16(b.z & 0xFFFFu).x);
    return shade_surface(vec3(rg, b_gloss.x), vec3(xy, z), vec4(normal, b_gloss.y), specular, emissive);
}

// Tonemapped values are summed as 24-bit fixed point: integer addition does
// not depend on the order of the list (which fragment took a pool block
// first), so the image is the same frame after frame; 32 samples of at most
// 2^24 each fit a uint.
const float FIXED_ONE = 16777216.0;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    uint p = sparse_pixel(pixel);
    uint flags = heads[2u * p + 1u];
    vec2 ndc = gl_FragCoord.xy / u_viewport * 2.0 - 1.0;
    vec3 background = shade_background(texelFetch(u_background, pixel, 0).rgb);
    bool has_first = (flags & SPARSE_FIRST) != 0u;
    uvec4 first_b = first_blocks[2u * p + 1u];
    vec3 first = has_first ? shade_block(first_blocks[2u * p], first_b, ndc) : background;
    int n = clamp(u_samples, 1, SPARSE_MAX_SAMPLES);
    if (n == 1 || (flags & (SPARSE_OVERFLOW | SPARSE_SINGLE)) != 0u || !sparse_in_region(gl_FragCoord.xy)) {
        o_color = vec4(first, 1.0);
        return;
    }

    bool tonemapped = u_tonemapped_average != 0;
    uvec3 fixed_sum = uvec3(0u);
    vec3 linear_sum = vec3(0.0);
    int covered = 0;
    uint seen = 0u;           // sample indices of the blocks summed so far
    bool same = true;         // every contributor has the radiance `first`
    if (has_first) {
        int count = int((first_b.z >> 16) & 0xFFu);
        fixed_sum += uvec3(round(tonemap_linear(first) * FIXED_ONE)) * uint(count);
        linear_sum += first * float(count);
        covered = count;
        seen = 1u;
    }
    // A list holds at most n - 1 blocks (each covers a sample sample 0's
    // does not); the bound, the index check and `seen` keep a damaged list
    // harmless.
    uint next = heads[2u * p];
    for (int k = 0; k < n && next != 0u; ++k) {
        uint index = next - 1u;
        if (index >= u_pool_capacity) {
            break;
        }
        uvec4 a = pool_blocks[2u * index];
        uvec4 b = pool_blocks[2u * index + 1u];
        int count = int((b.z >> 16) & 0xFFu);
        uint s = b.z >> 24;
        if (s < uint(n) && (seen & (1u << s)) == 0u && count > 0) {
            vec3 radiance = shade_block(a, b, ndc);
            same = same && radiance == first;
            fixed_sum += uvec3(round(tonemap_linear(radiance) * FIXED_ONE)) * uint(count);
            linear_sum += radiance * float(count);
            covered += count;
            seen |= 1u << s;
        }
        next = b.w;
    }
    // Samples no block covers show the background (with no first block,
    // sample 0 is one of them).
    int uncovered = max(n - covered, 0);
    if (uncovered > 0) {
        same = same && background == first;
        fixed_sum += uvec3(round(tonemap_linear(background) * FIXED_ONE)) * uint(uncovered);
        linear_sum += background * float(uncovered);
    }
    float total = float(covered + uncovered);
    if (same) {
        o_color = vec4(first, 1.0);
    } else if (tonemapped) {
        o_color = vec4(tonemap_linear_inverse(vec3(fixed_sum) / (FIXED_ONE * total)), 1.0);
    } else {
        o_color = vec4(linear_sum / total, 1.0);
    }
}
