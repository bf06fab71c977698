// What makes a pixel "complex" (its samples are not one surface, so the
// resolve's slow path blends them) and the selective-AA selection test,
// defined once for every shader that needs them: resolve.frag, the lab's
// complex_mask.frag and sparse.frag, and the viewer's complex view. The
// CPU reference (src/resolve/cpu.rs: uniform, Region::outside_window) is
// the only other copy; change both together.
//
// A pixel is uniform (sample 0 is its value) when every sample is the
// same surface as sample 0, complex otherwise.

// Samples i and 0 are the same surface: both background, or both geometry
// with equal keys. `key` is the depth key (view space's -z); equal keys are
// exact, so a pixel that passes resolves to its sample 0 bit for bit.
bool dmsaa_same_surface(bool bg_i, float key_i, bool bg_0, float key_0) {
    return bg_i == bg_0 && (bg_0 || key_i == key_0);
}

// The same with a whole key: a position (a world-space one's xyz, a
// view-space one's z) and the raw depth in w, all of which must agree (a
// half-float position rounds nearby depths to one value; see resolve.frag's
// keys_uniform).
bool dmsaa_same_surface(bool bg_i, vec4 key_i, bool bg_0, vec4 key_0) {
    return bg_i == bg_0 && (bg_0 || all(equal(key_i, key_0)));
}

// The same with a tolerance: geometry keys count as equal when they are at
// most `tolerance` times the nearer key apart (a NaN difference counts as
// equal; tolerance 0 is not the exact test: a difference may flush to zero).
// Method `complex` keeps this looser test: its mask decides which pixels are
// lit per sample, and the exact one would mark more of them (a measured
// fraction and the image would change).
bool dmsaa_same_surface_within(bool bg_i, float key_i, bool bg_0, float key_0, float tolerance) {
    return bg_i == bg_0
        && (bg_0 || !(abs(key_i - key_0) > tolerance * max(min(key_i, key_0), 0.0)));
}

// Selective AA by region: whether the pixel centre `c` (window pixels,
// origin bottom-left) is outside the rectangle (x0, y0, x1, y1), inside
// meaning x0 <= c < x1 ...
bool dmsaa_outside_rect(vec2 c, vec4 rect) {
    return any(lessThan(c, rect.xy)) || any(greaterThanEqual(c, rect.zw));
}

// ... or outside the ellipse (centre x, y, 1/radius x, y).
bool dmsaa_outside_ellipse(vec2 c, vec4 ellipse) {
    vec2 d = (c - ellipse.xy) * ellipse.zw;
    return dot(d, d) > 1.0;
}

// Selective AA by depth: a sample is near enough to be anti-aliased
// (geometry no farther than `max_depth`, the key's units).
bool dmsaa_within_depth(bool bg, float key, float max_depth) {
    return !bg && key <= max_depth;
}
