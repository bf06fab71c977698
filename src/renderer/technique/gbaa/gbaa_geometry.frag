// The G-buffer pass of method `gbaa`: the model shader geometry.frag,
// unchanged, with its main() renamed to model_main() by a #define in front
// of it, then this main(), which runs it and also writes where the
// fragment's triangle ends, for the GBAA post pass (gbaa.frag).
//
// Edges inside a smooth surface (g_blend = 0, see gbaa_geometry.geom) are
// left out: the triangle is taken to go on across them.
//
// Of the triangle's three edges (lines from gbaa_geometry.geom) the nearest
// along its own major axis is taken: the axis, x or y, along which the edge
// is crossed soonest (the one its normal leans towards). Along that axis
// and direction the distance to the triangle's boundary is written to
// o_edge (signed, in pixels, in .x for the x axis or .y for the y axis; the
// other channel holds GBAA_NO_EDGE), and the distance to the boundary the
// opposite way along the same axis to o_edge_far: a triangle thinner than
// a pixel has both of its sides inside the pixel. Distances are capped at
// GBAA_REACH pixels; only those under one pixel matter to the post pass.
//
// Defines from the renderer: GBAA_NO_EDGE, GBAA_REACH.

flat in vec3 g_edge0;
flat in vec3 g_edge1;
flat in vec3 g_edge2;
flat in vec3 g_blend;           // per edge: 1 = may be blended across, 0 = smooth interior

uniform vec2 u_viewport;        // width and height in pixels

out vec4 o_edge;
out vec4 o_edge_far;

// Signed distance in pixels from the point p (about the viewport centre) to a line.
float line_distance(vec3 line, vec2 p) {
    return dot(line, vec3(p, 1.0));
}

// How far p may move along the unit vector dir before it reaches the line;
// GBAA_NO_EDGE when moving that way does not bring it closer.
float crossing(vec3 line, vec2 p, vec2 dir) {
    float e = line_distance(line, p);
    float rate = dot(line.xy, dir);
    if (rate == 0.0 || e * rate > 0.0) {
        return GBAA_NO_EDGE;
    }
    return min(abs(e / rate), GBAA_REACH);
}

void main() {
    model_main();

    vec2 p = gl_FragCoord.xy - 0.5 * u_viewport;
    vec3 lines[3] = vec3[3](g_edge0, g_edge1, g_edge2);

    // The nearest edge along its own major axis decides axis and direction.
    float nearest = 1e30;
    vec2 dir = vec2(1.0, 0.0);
    for (int i = 0; i < 3; ++i) {
        if (g_blend[i] == 0.0) {
            continue;
        }
        vec2 n = lines[i].xy;
        bool along_x = abs(n.x) >= abs(n.y);
        float major = along_x ? n.x : n.y;
        if (major == 0.0) {
            continue;       // the far-away line of an edge with no length
        }
        float e = line_distance(lines[i], p);
        float d = abs(e / major);
        if (d < nearest) {
            nearest = d;
            // Moving against the sign of e * normal brings e towards 0.
            float towards = e * major > 0.0 ? -1.0 : 1.0;
            dir = along_x ? vec2(towards, 0.0) : vec2(0.0, towards);
        }
    }

    // Along that direction the boundary may still be another edge (near a
    // corner); the opposite way it is one of the other two.
    float ahead = GBAA_NO_EDGE;
    int ahead_edge = -1;
    for (int i = 0; i < 3; ++i) {
        if (g_blend[i] == 0.0) {
            continue;
        }
        float d = crossing(lines[i], p, dir);
        if (d < ahead) {
            ahead = d;
            ahead_edge = i;
        }
    }
    float behind = GBAA_NO_EDGE;
    for (int i = 0; i < 3; ++i) {
        if (i != ahead_edge && g_blend[i] != 0.0) {
            behind = min(behind, crossing(lines[i], p, -dir));
        }
    }

    ahead = min(ahead, GBAA_REACH);
    o_edge = dir.x != 0.0
        ? vec4(dir.x * ahead, GBAA_NO_EDGE, 0.0, 1.0)
        : vec4(GBAA_NO_EDGE, dir.y * ahead, 0.0, 1.0);
    o_edge_far = vec4(min(behind, GBAA_REACH), 0.0, 0.0, 1.0);
}
