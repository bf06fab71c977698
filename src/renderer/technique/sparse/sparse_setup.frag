// Between the depth pre-pass and the G-buffer pass of method `sparse`, one
// full-screen pass over the single-sample G-buffer's framebuffer: it empties
// every pixel's list (heads and flags to zero) and writes the depth of
// sample 0 (the surface a single-sample pixel shows) into the G-buffer's
// depth, which the decal hook reads and transparent objects are tested
// against. Compiled after sparse.frag.

uniform sampler2DMS u_depth;   // the pre-pass depth

layout(std430, binding = 0) writeonly buffer SparseHeads {
    uint heads[];
};

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    uint p = sparse_pixel(pixel);
    heads[2u * p] = 0u;
    heads[2u * p + 1u] = 0u;
    gl_FragDepth = texelFetch(u_depth, pixel, 0).r;
}
