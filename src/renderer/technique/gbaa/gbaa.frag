// The post pass of method `gbaa` (geometry-buffer anti-aliasing, after
// Persson): each pixel is blended with its neighbour across the triangle
// edge that crosses it, by the fraction of the pixel on the neighbour's
// side, in one bilinear fetch: the texture coordinate moves towards the
// neighbour by that fraction.
//
// Inputs, from the G-buffer pass (gbaa_geometry.frag):
//   u_edge      RG16F, the signed distance in pixels from the pixel centre
//               to the nearest edge of its triangle along x (.r) or y (.g);
//               the other channel, and both where no triangle was drawn,
//               hold GBAA_NO_EDGE;
//   u_edge_far  R16F, the distance to the triangle's boundary the opposite
//               way along the same axis.
// u_image is the tonemapped frame in an sRGB texture with linear filtering,
// so the fetches decode and blend in linear light; the result is encoded
// again (srgb_encode from tonemap.frag, compiled in front of this file with
// TONEMAP_FUNCTIONS_ONLY).
//
// Per pixel:
//  - an edge inside the pixel (distance d < 0.5): the neighbour beyond it
//    covers 0.5 - d of the pixel;
//  - (fix for converging edges, a) the triangle's other side inside the
//    pixel too (u_edge_far < 0.5): a triangle thinner than a pixel; the
//    pixel blends three colours, its own and both neighbours', each by its
//    coverage, in two fetches (their average, each moved twice as far);
//  - (fix b) a neighbour whose own edge points back at this pixel along the
//    same axis, at a distance that does not meet this pixel's edge, lies
//    beyond a different edge: something thin sits between the two pixel
//    centres that neither sampled, so neither takes the other's colour;
//  - no edge inside the pixel (background pixels always): a neighbour's
//    edge may still end inside it (the silhouette seen from outside), when
//    the neighbour's distance to its edge, or to its far side, pointing at
//    this pixel lies between 0.5 and 1; the largest such coverage is taken.
//
// With GBAA_SHOW_EDGES the pass writes what it would blend instead:
// red = coverage taken along x, green = along y, blue = the second
// neighbour's coverage of a three-colour pixel (each doubled, so a full
// half-pixel shows as 1); black = left as it is.
//
// Defines from the renderer: GBAA_NO_EDGE, GBAA_GAP (how far two pixels'
// edge distances may fall short of one pixel and still be one edge).

uniform sampler2D u_image;      // sRGB, linear filtering, clamped
uniform sampler2D u_edge;
uniform sampler2D u_edge_far;
uniform vec2 u_texel;           // 1 / size

out vec4 o_color;

// The axis direction (a unit step, pointing at the edge) and the distance
// of a pixel's nearest edge; distance GBAA_NO_EDGE where it has none.
void read_edge(ivec2 p, out ivec2 dir, out float dist) {
    vec2 e = texelFetch(u_edge, p, 0).rg;
    if (abs(e.x) <= abs(e.y)) {
        dir = ivec2(e.x < 0.0 ? -1 : 1, 0);
        dist = abs(e.x);
    } else {
        dir = ivec2(0, e.y < 0.0 ? -1 : 1);
        dist = abs(e.y);
    }
}

// Which of the four steps (+x, -x, +y, -y) a unit step is; i ^ 1 is the opposite.
int step_index(ivec2 d) {
    return d.x != 0 ? (d.x > 0 ? 0 : 1) : (d.y > 0 ? 2 : 3);
}

vec3 fetch(vec2 uv) {
    return textureLod(u_image, uv, 0.0).rgb;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_edge, 0) - 1;
    vec2 uv = gl_FragCoord.xy * u_texel;

    // This pixel's edge and far side, and the four neighbours' edges
    // (read once: fix b and the neighbour check both need them); beyond
    // the image there is no edge.
    ivec2 dir;
    float dist;
    read_edge(p, dir, dist);
    float far = texelFetch(u_edge_far, p, 0).r;
    ivec2 steps[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    ivec2 n_dir[4];
    float n_dist[4];
    for (int i = 0; i < 4; ++i) {
        ivec2 q = p + steps[i];
        read_edge(clamp(q, ivec2(0), last), n_dir[i], n_dist[i]);
        if (any(lessThan(q, ivec2(0))) || any(greaterThan(q, last))) {
            n_dist[i] = GBAA_NO_EDGE;
        }
    }

    float ahead = 0.0;      // coverage of the neighbour at p + dir
    float behind = 0.0;     // coverage of the neighbour at p - dir
    if (dist < 0.5) {
        ahead = 0.5 - dist;
        behind = max(0.5 - far, 0.0);
        // Fix (b): a neighbour whose edge points back here, short of ours.
        int a = step_index(dir);
        if (n_dir[a] == -dir && dist + n_dist[a] < 1.0 - GBAA_GAP) {
            ahead = 0.0;
        }
        int b = a ^ 1;
        if (n_dir[b] == dir && far + n_dist[b] < 1.0 - GBAA_GAP) {
            behind = 0.0;
        }
    } else {
        // Neighbours whose edge, or far side, ends inside this pixel.
        for (int i = 0; i < 4; ++i) {
            float beyond = n_dir[i] == -steps[i] ? n_dist[i] : GBAA_NO_EDGE;
            if (n_dir[i] == steps[i] && n_dist[i] < 1.0) {
                // Its nearest edge points away from here, close: a thin
                // triangle, whose far side points here.
                beyond = texelFetch(u_edge_far, p + steps[i], 0).r;
            }
            float covered = beyond - 0.5;
            if (beyond < 1.0 && covered > ahead) {
                ahead = covered;
                dir = steps[i];
            }
        }
    }

#ifdef GBAA_SHOW_EDGES
    vec2 shown = abs(vec2(dir)) * 2.0 * ahead;
    o_color = vec4(shown, 2.0 * behind, 1.0);
#else
    // One bilinear fetch, moved towards the neighbour ahead by its share,
    // blends the two. A pixel of three colours averages two fetches, each
    // moved twice as far: the neighbours weigh `ahead` and `behind`, the
    // pixel the rest.
    vec2 step_uv = vec2(dir) * u_texel;
    vec3 color = fetch(uv + (behind > 0.0 ? 2.0 : 1.0) * ahead * step_uv);
    if (behind > 0.0) {
        color = 0.5 * (color + fetch(uv - 2.0 * behind * step_uv));
    }
    o_color = vec4(srgb_encode(color), 1.0);
#endif
}
