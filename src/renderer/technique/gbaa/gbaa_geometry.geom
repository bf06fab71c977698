// The geometry stage of method `gbaa`'s G-buffer pass (geometry-buffer
// anti-aliasing). It passes each triangle through unchanged and gives its
// three fragments' worth of edge information: the screen-space lines of the
// triangle's three edges, the same for every vertex (flat).
//
// geometry.vert is compiled with its outputs renamed to vert_* (a GLSL 1.50
// geometry shader cannot take in and give out variables of one name); this
// stage gives them out again under their own names for geometry.frag.
//
// An edge inside a smooth, front-facing surface (both of its vertices
// shaded with normals that differ from the triangle's own, so the surface
// bends on beyond the edge, and that face the eye) is no edge to blend
// across: what lies beyond it in the pixel is more of the same surface,
// whatever the neighbouring pixel shows. (A cylinder narrower than a few
// pixels has faces narrower than one; blending across them would mix in the
// sky beyond the silhouette where the next face is.) g_blend marks the
// edges that may be silhouettes or creases: 1 to blend across, 0 not.
//
// A triangle of less than GBAA_MIN_AREA square pixels gets no edges at
// all: it is a speck of something a pixel or smaller (a greeble, a face of
// a thin cylinder), whose edges do not separate this pixel's colour from
// the neighbours' (what lies beyond them is more of the speck's object, not
// the neighbouring pixel), so its pixels stay as they were sampled.
//
// A line is kept as (a, b, c) with a*x + b*y + c = signed distance in pixels
// from the window point (x, y), measured from the centre of the viewport
// (small coordinates keep f32 rounding in c small). It is the cross product
// of the two vertices in homogeneous window coordinates, which is the
// projected edge even when a vertex lies behind the eye (w < 0), where the
// divided position would not be.

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

in vec3 vert_position[];
in vec3 vert_normal[];
in vec2 vert_uv[];

uniform vec2 u_viewport;        // width and height in pixels

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
flat out vec3 g_edge0;          // the edge from vertex 1 to vertex 2
flat out vec3 g_edge1;          // from vertex 2 to vertex 0
flat out vec3 g_edge2;          // from vertex 0 to vertex 1
flat out vec3 g_blend;          // per edge: 1 = blend across it, 0 = smooth interior

// Cosine of the angle between a vertex normal and the triangle's normal
// above which the vertex counts as flat-shaded (a crease may follow).
#define FLAT_COS 0.999
// A vertex normal faces the eye when its cosine with the direction to the
// eye exceeds this (grazing normals are left to the silhouette).
#define FACING_COS 0.1

// Clip coordinates to homogeneous window coordinates about the viewport centre.
vec3 window_homogeneous(vec4 clip) {
    return vec3(0.5 * u_viewport * clip.xy, clip.w);
}

// The line through two homogeneous points, scaled so that (a, b) is a unit
// normal. An edge that projects to a point has no line: it is put
// infinitely far away (a fragment never lies on such a triangle anyway).
vec3 edge_line(vec3 p, vec3 q) {
    vec3 line = cross(p, q);
    float len = length(line.xy);
    return len > 1e-20 ? line / len : vec3(0.0, 0.0, 1e30);
}

// The triangle's area in pixels, or infinity when a vertex lies behind the
// eye (such a triangle is large on screen anyway).
float pixel_area() {
    vec4 c0 = gl_in[0].gl_Position;
    vec4 c1 = gl_in[1].gl_Position;
    vec4 c2 = gl_in[2].gl_Position;
    if (c0.w <= 0.0 || c1.w <= 0.0 || c2.w <= 0.0) {
        return 1e30;
    }
    vec2 a = 0.5 * u_viewport * c0.xy / c0.w;
    vec2 b = 0.5 * u_viewport * c1.xy / c1.w;
    vec2 c = 0.5 * u_viewport * c2.xy / c2.w;
    return 0.5 * abs((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
}

// Whether the surface bends on beyond vertex i, facing the eye: its shading
// normal (turned by `side` as the fragment shader turns it) is not the
// triangle's normal `face` and points towards the eye.
bool bends_on(int i, vec3 face, float side) {
    float len = length(vert_normal[i]);
    float eye = length(vert_position[i]);
    if (len < 1e-20 || eye < 1e-20) {
        return false;
    }
    vec3 n = side * vert_normal[i] / len;
    return dot(n, face) < FLAT_COS && dot(n, -vert_position[i]) > FACING_COS * eye;
}

void main() {
    // The triangle's view-space normal, turned to the eye; a back face (of
    // a double-sided material) is shaded with flipped normals.
    vec3 face = cross(vert_position[1] - vert_position[0], vert_position[2] - vert_position[0]);
    float face_len = length(face);
    face = face_len > 1e-30 ? face / face_len : vec3(0.0, 0.0, 1.0);
    float side = dot(face, -vert_position[0]) < 0.0 ? -1.0 : 1.0;
    face *= side;
    bool b0 = bends_on(0, face, side);
    bool b1 = bends_on(1, face, side);
    bool b2 = bends_on(2, face, side);
    // Edge i runs between the other two vertices.
    vec3 blend = vec3(b1 && b2 ? 0.0 : 1.0, b2 && b0 ? 0.0 : 1.0, b0 && b1 ? 0.0 : 1.0);
    if (pixel_area() < GBAA_MIN_AREA) {
        blend = vec3(0.0);
    }

    vec3 p0 = window_homogeneous(gl_in[0].gl_Position);
    vec3 p1 = window_homogeneous(gl_in[1].gl_Position);
    vec3 p2 = window_homogeneous(gl_in[2].gl_Position);
    vec3 e0 = edge_line(p1, p2);
    vec3 e1 = edge_line(p2, p0);
    vec3 e2 = edge_line(p0, p1);
    for (int i = 0; i < 3; ++i) {
        v_position = vert_position[i];
        v_normal = vert_normal[i];
        v_uv = vert_uv[i];
        g_edge0 = e0;
        g_edge1 = e1;
        g_edge2 = e2;
        g_blend = blend;
        gl_Position = gl_in[i].gl_Position;
        EmitVertex();
    }
    EndPrimitive();
}
