// Shared by the passes of method `sparse` (the per-pixel linked-list
// G-buffer): the layout of the per-pixel heads and of a block, and the
// screen region that is anti-aliased. Compiled in front of
// sparse_setup.frag, sparse_geometry.frag and sparse_lighting.frag with
// GL_ARB_shader_storage_buffer_object and GL_ARB_shading_language_420pack
// (and _packing where blocks are packed or unpacked).
//
// Heads: two uints per pixel p (row-major from the bottom row, as
// gl_FragCoord counts): heads[2p] is the first pool block of the pixel's
// list, as pool index + 1 (0 ends the list); heads[2p + 1] holds the
// SPARSE_* flags below. sparse_setup.frag zeroes both every frame.
//
// A block is two uvec4s (32 bytes), the G-buffer attributes of one
// fragment (one triangle in one pixel) and where it is visible:
//   a.x  base colour r, g            packHalf2x16 (as the RGBA16F attachment)
//   a.y  base colour b, gloss        packHalf2x16
//   a.z  F0 rgb, metallic            packUnorm4x8 (as the RGBA8 attachment)
//   a.w  unit normal                 octahedral, packSnorm2x16
//   b.x  view-space z                float bits; x and y follow from the
//                                    pixel centre through the projection
//   b.y  emission r, g               packHalf2x16
//   b.z  emission b (low 16 bits), then the number of samples the fragment
//        is visible in (bits 16-23) and the first of them (bits 24-31)
//   b.w  the next pool block of the pixel, as index + 1 (0: none)
// The first block area holds, for every pixel, the block of the fragment
// that is visible in sample 0; the other fragments' blocks come from the
// pool.

#define SPARSE_FIRST 1u      // the first block area holds this frame's sample-0 fragment
#define SPARSE_OVERFLOW 2u   // a block did not fit in the pool: the pixel falls back to sample 0
#define SPARSE_SINGLE 4u     // a fragment here is not to be anti-aliased (object flag, depth)

#define SPARSE_REGION_EVERYWHERE 0
#define SPARSE_REGION_RECT 2
#define SPARSE_REGION_ELLIPSE 3

uniform uint u_width;          // pixels per row of the heads and first blocks
uniform int u_region_kind;     // SPARSE_REGION_*
uniform vec4 u_region;         // rect: x0, y0, x1, y1; ellipse: centre x, y, 1/radius x, y
                               // (window pixels: resolve::Region::window_uniform)

// Whether the pixel whose centre is at `frag` (gl_FragCoord.xy) is in the
// anti-aliased region; outside it every pixel shows its sample 0. The test
// is the resolve's (complex.glsl, composed in front of this file).
bool sparse_in_region(vec2 frag) {
    if (u_region_kind == SPARSE_REGION_RECT) {
        return !dmsaa_outside_rect(frag, u_region);
    }
    if (u_region_kind == SPARSE_REGION_ELLIPSE) {
        return !dmsaa_outside_ellipse(frag, u_region);
    }
    return true;
}

uint sparse_pixel(ivec2 pixel) {
    return uint(pixel.y) * u_width + uint(pixel.x);
}
