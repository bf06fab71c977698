// SMAA pass 2, blending weights. For each edge a pixel owns (its top edge,
// a horizontal line between it and the pixel above; its left edge, a
// vertical line between it and the pixel to the left):
//  1. walk along the line both ways to its ends, two pixels per fetch: a
//     bilinear fetch a quarter pixel from the nearer pixel's centre gives
//     0.75 * near + 0.25 * far for the line's edge flag and the crossing
//     flag, and the search table says how many of the two the line covers
//     and whether it goes on (see smaa_tables.rs);
//  2. read the crossing edges at both ends, on this pixel's side of the
//     line and across it;
//  3. look up the areas for that pattern and those distances in the area
//     table: what this pixel takes from across the line, what the pixel
//     across takes from it;
//  4. with corner rounding, an end whose crossing edge goes on past the
//     line's row (a real corner, not a one-pixel step) keeps only that share
//     of its smoothing.
//  5. with diagonal steps, a pixel in a run of one-pixel steps along a
//     diagonal (at least two) takes its weights from the run instead: count
//     the run's cells both ways, read how the staircase goes on past each end
//     (flatter, steeper or neither), and look the areas up in the diagonal
//     table, all across the cells' horizontal edges (the blend then mixes
//     along that axis alone). A rising run's cell is a pixel with a left and
//     a top edge; a falling run's, a pixel with a left edge over a pixel with
//     a top edge, whose weights that lower pixel holds.
// Horizontal lines start at the left, vertical ones at the top; "this
// pixel's side" of a vertical line is the right.

uniform sampler2D u_edges;     // RG8: left (.r), top (.g); linear filtering
uniform sampler2D u_area;      // RG8 area table
uniform sampler2D u_search;    // R8 search table
uniform sampler2D u_diagonal;  // RG8 diagonal table
uniform int u_search_steps;
uniform int u_diagonal_steps;  // cells walked each way along a diagonal; 0: off
uniform int u_corners;         // 1: tell corners from steps
uniform float u_corner;        // the share of smoothing a corner keeps

out vec4 o_weights;

#define MAX_DISTANCE 64
#define DIAGONAL_MAX_DISTANCE 32
#define TO_START 0
#define TO_END 1

vec2 edges_at(ivec2 p) {
    ivec2 size = textureSize(u_edges, 0);
    if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, size))) {
        return vec2(0.0);
    }
    return texelFetch(u_edges, p, 0).rg;
}

bool left_edge(ivec2 p) { return edges_at(p).r > 0.5; }
bool top_edge(ivec2 p) { return edges_at(p).g > 0.5; }

// How many pixels past `p` the line goes along `dir`, at most `limit`.
// `vertical`: the line is a run of left edges (else of top edges).
int walk(ivec2 p, ivec2 dir, bool vertical, int table, int limit) {
    vec2 size = vec2(textureSize(u_edges, 0));
    int d = 0;
    for (int i = 0; i < u_search_steps; ++i) {
        vec2 near = vec2(p + dir * (d + 1)) + 0.5;
        vec2 e = textureLod(u_edges, (near + 0.25 * vec2(dir)) / size, 0.0).rg;
        float along = vertical ? e.r : e.g;
        float crossing = vertical ? e.g : e.r;
        ivec2 t = ivec2(table * 5 + int(round(4.0 * crossing)), int(round(4.0 * along)));
        int code = int(round(3.0 * texelFetch(u_search, t, 0).r));
        d += min(code, 2);
        if (code != 3) {
            break;
        }
    }
    return min(d, limit);
}

int crossing(bool pixel_side, bool other_side) {
    return int(pixel_side) + 2 * int(other_side);
}

vec2 area(int at_start, int at_end, int to_start, int to_end) {
    ivec2 t = ivec2(at_start * MAX_DISTANCE + min(to_start, MAX_DISTANCE - 1),
                    at_end * MAX_DISTANCE + min(to_end, MAX_DISTANCE - 1));
    return texelFetch(u_area, t, 0).rg;
}

// The areas of a line with crossings `cs`, `ce` at distances `ds`, `de`;
// `sharp_s`, `sharp_e`: the crossing at that end is a corner.
vec2 weigh(int cs, int ce, int ds, int de, bool sharp_s, bool sharp_e) {
    if (u_corners == 0) {
        return area(cs, ce, ds, de);
    }
    // The ends add independently: scale each by its own corner.
    return area(cs, 0, ds, de) * (sharp_s ? u_corner : 1.0)
         + area(0, ce, ds, de) * (sharp_e ? u_corner : 1.0);
}

// A rising run's cell: edges on its left and top.
bool rising_cell(ivec2 q) { return left_edge(q) && top_edge(q); }

// A falling run's cell, at the lower of its two pixels: a top edge here and
// a left edge on the pixel above.
bool falling_cell(ivec2 b) { return top_edge(b) && left_edge(b + ivec2(0, 1)); }

// How many cells follow `p` along `dir`.
int run(ivec2 p, ivec2 dir, bool rising) {
    int d = 0;
    for (int i = 0; i < u_diagonal_steps; ++i) {
        ivec2 q = p + dir * (d + 1);
        if (!(rising ? rising_cell(q) : falling_cell(q))) {
            break;
        }
        d += 1;
    }
    return d;
}

// 0 straight, 1 flatter, 2 steeper (both or neither: straight; and a run
// the walk cut short, `cells` = the steps, whose next cell would read as
// flatter).
int diagonal_end(bool flatter, bool steeper, int cells) {
    if (cells >= u_diagonal_steps || flatter == steeper) {
        return 0;
    }
    return flatter ? 1 : 2;
}

vec2 diagonal_area(int at_start, int at_end, int back, int forward) {
    ivec2 t = ivec2(at_start * DIAGONAL_MAX_DISTANCE + min(back, DIAGONAL_MAX_DISTANCE - 1),
                    at_end * DIAGONAL_MAX_DISTANCE + min(forward, DIAGONAL_MAX_DISTANCE - 1));
    return texelFetch(u_diagonal, t, 0).rg;
}

void main() {
    ivec2 size = textureSize(u_edges, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec2 own = texelFetch(u_edges, p, 0).rg;
    vec4 weights = vec4(0.0);

    if (own.g > 0.5) {
        // The line between this row and the one above, left to right.
        int ds = left_edge(p) ? 0 : walk(p, ivec2(-1, 0), false, TO_START, p.x);
        int de = walk(p, ivec2(1, 0), false, TO_END, size.x - 1 - p.x);
        ivec2 s = p - ivec2(ds, 0);
        ivec2 e = p + ivec2(de + 1, 0);   // the pixel past the end
        bool sp = left_edge(s), so = left_edge(s + ivec2(0, 1));
        bool ep = left_edge(e), eo = left_edge(e + ivec2(0, 1));
        bool sharp_s = sp ? left_edge(s + ivec2(0, -1)) : left_edge(s + ivec2(0, 2));
        bool sharp_e = ep ? left_edge(e + ivec2(0, -1)) : left_edge(e + ivec2(0, 2));
        weights.rg = weigh(crossing(sp, so), crossing(ep, eo), ds, de, sharp_s, sharp_e);
    }

    if (own.r > 0.5) {
        // The line between this column and the one to the left, top to bottom.
        int ds = top_edge(p) ? 0 : walk(p, ivec2(0, 1), true, TO_START, size.y - 1 - p.y);
        int de = walk(p, ivec2(0, -1), true, TO_END, p.y);
        ivec2 s = p + ivec2(0, ds);
        ivec2 e = p - ivec2(0, de + 1);   // the pixel past the end
        bool sp = top_edge(s), so = top_edge(s + ivec2(-1, 0));
        bool ep = top_edge(e), eo = top_edge(e + ivec2(-1, 0));
        bool sharp_s = sp ? top_edge(s + ivec2(1, 0)) : top_edge(s + ivec2(-2, 0));
        bool sharp_e = ep ? top_edge(e + ivec2(1, 0)) : top_edge(e + ivec2(-2, 0));
        weights.ba = weigh(crossing(sp, so), crossing(ep, eo), ds, de, sharp_s, sharp_e);
    }

    if (u_diagonal_steps > 0) {
        if (rising_cell(p)) {
            int back = run(p, ivec2(-1, -1), true);
            int forward = run(p, ivec2(1, 1), true);
            if (back + forward > 0) {
                ivec2 s = p - ivec2(back);
                ivec2 e = p + ivec2(forward);
                int cs = diagonal_end(top_edge(s - ivec2(1, 1)), left_edge(s - ivec2(0, 1)), back);
                int ce = diagonal_end(top_edge(e + ivec2(1, 0)), left_edge(e + ivec2(0, 1)), forward);
                weights = vec4(diagonal_area(cs, ce, back, forward), 0.0, 0.0);
            }
        } else if (falling_cell(p)) {
            // The run's frame is this one mirrored top to bottom: what the
            // cell (the pixel above) takes is what this pixel gives it.
            int back = run(p, ivec2(-1, 1), false);
            int forward = run(p, ivec2(1, -1), false);
            if (back + forward > 0) {
                ivec2 s = p + ivec2(-back, back);
                ivec2 e = p + ivec2(forward, -forward);
                int cs = diagonal_end(top_edge(s + ivec2(-1, 1)), left_edge(s + ivec2(0, 2)), back);
                int ce = diagonal_end(top_edge(e + ivec2(1, 0)), left_edge(e), forward);
                weights.rg = diagonal_area(cs, ce, back, forward).yx;
            }
        }
        // The upper pixel of a falling run's cell: its left edge belongs to
        // the run, which the pixel below weighs.
        ivec2 b = p - ivec2(0, 1);
        if (falling_cell(b) && run(b, ivec2(-1, 1), false) + run(b, ivec2(1, -1), false) > 0) {
            weights.ba = vec2(0.0);
        }
    }

    o_weights = weights;
}
