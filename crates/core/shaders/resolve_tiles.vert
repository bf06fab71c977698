// The resolve's slow tiles (src/resolve/tiles.rs): two triangles per
// TILE_SIZE x TILE_SIZE tile, generated from gl_VertexID with no vertex
// buffer. A tile is drawn only when its classification (u_tiles: 1.0 = some
// pixel needs the slow path) says so; the others collapse to a point outside
// the viewport, so the rasteriser never visits them.

uniform sampler2D u_tiles;
uniform ivec2 u_size;        // the resolve target's size in pixels

void main() {
    int tile = gl_VertexID / 6;
    int corner = gl_VertexID - tile * 6;
    ivec2 grid = textureSize(u_tiles, 0);
    ivec2 t = ivec2(tile - (tile / grid.x) * grid.x, tile / grid.x);
    bool slow = texelFetch(u_tiles, t, 0).r > 0.5;
    // Corners of the two triangles: (0,0) (1,0) (0,1) and (0,1) (1,0) (1,1).
    ivec2 c = ivec2(corner == 1 || corner == 4 || corner == 5 ? 1 : 0,
                    corner == 2 || corner == 3 || corner == 5 ? 1 : 0);
    vec2 pixel = vec2(min((t + c) * TILE_SIZE, u_size));
    vec2 ndc = pixel / vec2(u_size) * 2.0 - 1.0;
    gl_Position = slow ? vec4(ndc, 0.0, 1.0) : vec4(-2.0, -2.0, 0.0, 1.0);
}
