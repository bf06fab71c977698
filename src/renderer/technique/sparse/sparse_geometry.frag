// The G-buffer pass of method `sparse`: the model shader geometry.frag,
// unchanged, with its main() renamed to model_main() by a #define in front
// of it, then this main(), which packs what model_main() wrote into one
// block per fragment instead of one G-buffer texel per sample. Compiled
// after geometry.frag and sparse.frag with GL_ARB_shader_storage_buffer_object,
// _shader_atomic_counters, _gpu_shader5, _shading_language_packing,
// _shading_language_420pack, _shader_image_load_store and _post_depth_coverage.
//
// It runs once per pixel and triangle (no sample shading) into a
// multisampled framebuffer that has only the pre-pass depth and a stencil
// cleared to 0. Depth test EQUAL, no depth write; stencil test EQUAL 0 and
// incremented to 1 where the depth test passes; both tests early (before this
// shader), and with post_depth_coverage gl_SampleMaskIn holds the samples
// that passed them: the samples this fragment is the visible surface of.
// The stencil bit is what keeps blocks unique: where triangles intersect
// or lie in one plane, two fragments can have bitwise the same depth in a
// sample, and both would pass EQUAL; the first one drawn claims the sample
// (as the depth test LESS of a multisampled G-buffer keeps the first one
// drawn) and the later one fails the stencil test there. So every visible
// sample belongs to exactly one fragment, and every fragment visible in at
// least one sample writes exactly one block.
//
// The fragment that owns sample 0 writes the pixel's pre-allocated first
// block; the others take a block from the pool with an atomic counter,
// bounds-checked: past u_pool_capacity nothing is written, the pixel is
// flagged SPARSE_OVERFLOW (counted once in u_overflow_pixels) and falls
// back to its first block. Outside the anti-aliased region, and in pixels
// where a visible fragment is beyond u_max_depth or belongs to an object
// that is not anti-aliased (SPARSE_SINGLE), only the first block is kept.

layout(early_fragment_tests) in;
layout(post_depth_coverage) in;

layout(std430, binding = 0) buffer SparseHeads {
    uint heads[];
};
layout(std430, binding = 1) writeonly buffer SparseFirstBlocks {
    uvec4 first_blocks[];
};
layout(std430, binding = 2) writeonly buffer SparsePoolBlocks {
    uvec4 pool_blocks[];
};
layout(binding = 0, offset = 0) uniform atomic_uint u_pool_next;
layout(binding = 0, offset = 4) uniform atomic_uint u_overflow_pixels;

uniform uint u_pool_capacity;     // blocks in the pool
uniform int u_object_antialias;   // 0: this object's pixels show sample 0 only
uniform float u_max_depth;        // view distance beyond which a fragment is not anti-aliased

// A unit vector in octahedral coordinates (both in [-1, 1]).
vec2 octahedral_encode(vec3 n) {
    n /= max(abs(n.x) + abs(n.y) + abs(n.z), 1e-20);
    vec2 e = n.xy;
    if (n.z < 0.0) {
        vec2 signs = vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
        e = (1.0 - abs(e.yx)) * signs;
    }
    return e;
}

void main() {
    uint covered = uint(gl_SampleMaskIn[0]);
    if (covered == 0u) {
        return;
    }
    model_main();

    uint p = sparse_pixel(ivec2(gl_FragCoord.xy));
    bool antialiased = u_object_antialias != 0 && dmsaa_within_depth(false, -o_position.z, u_max_depth);
    if (!antialiased) {
        atomicOr(heads[2u * p + 1u], SPARSE_SINGLE);
    }
    uint count = uint(bitCount(covered));
    uint first_sample = uint(findLSB(covered));
    uvec4 a = uvec4(
        packHalf2x16(o_color.rg),
        packHalf2x16(vec2(o_color.b, o_normal.w)),
        packUnorm4x8(o_specular),
        packSnorm2x16(octahedral_encode(o_normal.xyz)));
    uvec4 b = uvec4(
        floatBitsToUint(o_position.z),
        packHalf2x16(o_emissive.rg),
        (packHalf2x16(vec2(o_emissive.b, 0.0)) & 0xFFFFu) | (count << 16) | (first_sample << 24),
        0u);

    if ((covered & 1u) != 0u) {
        first_blocks[2u * p] = a;
        first_blocks[2u * p + 1u] = b;
        atomicOr(heads[2u * p + 1u], SPARSE_FIRST);
        return;
    }
    // A pixel that shows sample 0 only needs no other block. (The flags may
    // not be final yet; a block taken before SPARSE_SINGLE is set is unused.)
    if (!antialiased || !sparse_in_region(gl_FragCoord.xy)
            || (heads[2u * p + 1u] & (SPARSE_SINGLE | SPARSE_OVERFLOW)) != 0u) {
        return;
    }
    uint index = atomicCounterIncrement(u_pool_next);
    if (index >= u_pool_capacity) {
        uint before = atomicOr(heads[2u * p + 1u], SPARSE_OVERFLOW);
        if ((before & SPARSE_OVERFLOW) == 0u) {
            atomicCounterIncrement(u_overflow_pixels);
        }
        return;
    }
    b.w = atomicExchange(heads[2u * p], index + 1u);
    pool_blocks[2u * index] = a;
    pool_blocks[2u * index + 1u] = b;
}
