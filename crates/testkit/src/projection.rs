//! Column-major GL perspective matrices, as hosts upload them.

/// A standard GL perspective matrix; `far = None` is infinite.
pub fn perspective(fov_y: f64, aspect: f64, near: f64, far: Option<f64>) -> [f64; 16] {
    let (p22, p23) = match far {
        Some(far) => ((far + near) / (near - far), 2.0 * far * near / (near - far)),
        None => (-1.0, -2.0 * near),
    };
    projection_matrix(fov_y, aspect, p22, p23)
}

/// Reversed-Z for `GL_ZERO_TO_ONE` depth: near → 1, far → 0; `far = None` is infinite.
pub fn perspective_reversed(fov_y: f64, aspect: f64, near: f64, far: Option<f64>) -> [f64; 16] {
    let (p22, p23) = match far {
        Some(far) => (near / (far - near), far * near / (far - near)),
        None => (0.0, near),
    };
    projection_matrix(fov_y, aspect, p22, p23)
}

/// A column-major perspective matrix with the given depth terms.
fn projection_matrix(fov_y: f64, aspect: f64, p22: f64, p23: f64) -> [f64; 16] {
    let f = 1.0 / (fov_y / 2.0).tan();
    let mut m = [0.0; 16];
    m[0] = f / aspect;
    m[5] = f;
    m[10] = p22;
    m[11] = -1.0;
    m[14] = p23;
    m
}

/// The matrix as a host uploads it, in f32.
pub fn to_f32(m: &[f64; 16]) -> [f32; 16] {
    m.map(|v| v as f32)
}

/// The frame the resolve is given for a draw with `projection`: the matrix
/// as the host uploads it (f32), in standard or reversed-Z depth.
pub fn frame(projection: &[f64; 16], reversed: bool) -> deferred_msaa::Frame {
    let mode = if reversed {
        deferred_msaa::DepthMode::ReversedZ
    } else {
        deferred_msaa::DepthMode::Standard
    };
    deferred_msaa::Frame::from_matrix(to_f32(projection)).with_depth_mode(mode)
}
