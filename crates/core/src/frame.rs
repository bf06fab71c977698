//! What a host passes to the resolve each frame: its projection, and how its
//! depth buffer is stored.
//!
//! Everything else (samples, rules, key source, method, window, selection,
//! memory budget) is set once in
//! [`RetrofitOptions`](crate::RetrofitOptions). The resolve needs the
//! projection for two things: to turn depth-buffer values back into view
//! distances (the depth key, when no position attachment carries it), and to
//! know how large a pixel is at distance 1 (the closeness window scales
//! with it).

use crate::resolve::DepthProjection;
use crate::{Error, Result};

/// One frame's camera facts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The projection the geometry pass used.
    pub projection: Projection,
    /// How depth values are stored and what the depth buffer is cleared to.
    pub depth_mode: DepthMode,
    /// The view matrix (column-major), for a host whose position attachment
    /// holds world-space positions
    /// ([`PositionSpace::World`](crate::retrofit::PositionSpace::World)).
    pub view: Option<[f32; 16]>,
}

/// A perspective projection, given either way a host keeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// The 4x4 matrix, column-major (as `glUniformMatrix4fv` takes it
    /// untransposed), OpenGL's right-handed convention: `w_clip = −z_view`.
    /// Reversed-Z and infinite-far matrices work as they are; say the
    /// depth mode with [`Frame::with_depth_mode`].
    Matrix([f32; 16]),
    /// The terms a matrix would be built from. With
    /// [`DepthMode::ReversedZ`] the near plane maps to depth 1.
    Perspective {
        /// Vertical field of view in radians, in `(0, π)`.
        fov_y: f32,
        /// Distance of the near plane, above 0.
        near: f32,
        /// Distance of the far plane, beyond `near`; `None` for an infinite far plane.
        far: Option<f32>,
    },
}

/// How the depth buffer holds depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthMode {
    /// OpenGL's default: NDC depth in `[−1, 1]`, stored as `(z + 1) / 2`,
    /// the near plane at 0, cleared to 1.
    #[default]
    Standard,
    /// `glClipControl(…, GL_ZERO_TO_ONE)`: NDC depth stored as it is, the
    /// near plane at 0, cleared to 1.
    ZeroToOne,
    /// Reversed-Z: `GL_ZERO_TO_ONE`, the near plane at 1, the far plane (or
    /// infinity) at 0, cleared to 0 with a `GL_GREATER` depth test.
    ReversedZ,
}

impl DepthMode {
    /// Whether NDC depth is stored as it is (`GL_ZERO_TO_ONE`).
    pub fn zero_to_one(self) -> bool {
        !matches!(self, DepthMode::Standard)
    }

    /// The value the depth buffer is cleared to: where nothing was drawn.
    pub fn clear_depth(self) -> f64 {
        match self {
            DepthMode::ReversedZ => 0.0,
            DepthMode::Standard | DepthMode::ZeroToOne => 1.0,
        }
    }
}

impl Frame {
    /// A frame seen through the column-major projection matrix `m`, with
    /// OpenGL's default depth mode.
    pub fn from_matrix(m: [f32; 16]) -> Self {
        Frame {
            projection: Projection::Matrix(m),
            depth_mode: DepthMode::Standard,
            view: None,
        }
    }

    /// A frame seen through a symmetric perspective projection, with
    /// OpenGL's default depth mode.
    pub fn perspective(fov_y: f32, near: f32, far: Option<f32>) -> Self {
        Frame {
            projection: Projection::Perspective { fov_y, near, far },
            depth_mode: DepthMode::Standard,
            view: None,
        }
    }

    /// The same frame with another depth mode.
    pub fn with_depth_mode(self, depth_mode: DepthMode) -> Self {
        Frame { depth_mode, ..self }
    }

    /// The same frame with its view matrix (column-major), which a
    /// world-space position attachment needs.
    pub fn with_view(self, view: [f32; 16]) -> Self {
        Frame {
            view: Some(view),
            ..self
        }
    }

    /// The view matrix's third row, `(m[2], m[6], m[10], m[14])`: what turns
    /// a world-space position into view-space z.
    pub fn view_row(&self) -> Option<[f64; 4]> {
        self.view.map(|m| [m[2], m[6], m[10], m[14]].map(f64::from))
    }

    /// The depth linearisation and the vertical field of view, checked:
    /// a matrix must be a GL perspective projection (`m[11] = −1`,
    /// `m[15] = 0`), since the window scales with distance.
    pub fn depth_terms(&self) -> Result<(DepthProjection, f64)> {
        let mode = self.depth_mode;
        let (p22, p23, fov_y) = match self.projection {
            Projection::Matrix(m) => {
                let m = m.map(f64::from);
                let perspective = (m[11] + 1.0).abs() <= 1e-6 && m[15].abs() <= 1e-6;
                if !perspective || !m.iter().all(|v| v.is_finite()) {
                    return Err(Error::invalid(format!(
                        "the projection matrix is not an OpenGL perspective projection \
                         (m[11] = {}, m[15] = {}; expected -1 and 0): the resolve's depth \
                         window scales with distance, so orthographic projections are not supported",
                        m[11], m[15]
                    )));
                }
                if m[5] == 0.0 || m[14] == 0.0 {
                    return Err(Error::invalid(format!(
                        "the projection matrix has m[5] = {} and m[14] = {}; both must be non-zero",
                        m[5], m[14]
                    )));
                }
                // m[5] = 1 / tan(fov_y / 2); a y-flipping host makes it negative.
                (m[10], m[14], 2.0 * (1.0 / m[5].abs()).atan())
            }
            Projection::Perspective { fov_y, near, far } => {
                let (fov_y, n) = (f64::from(fov_y), f64::from(near));
                let far = far.map(f64::from);
                let valid_far = far.is_none_or(|f| f.is_finite() && f > n);
                let valid = fov_y > 0.0 && fov_y < std::f64::consts::PI && n > 0.0 && n.is_finite();
                if !(valid && valid_far) {
                    return Err(Error::invalid(format!(
                        "a perspective projection needs 0 < fov_y < pi, near > 0 and far beyond near, \
                         got fov_y {fov_y}, near {n}, far {far:?}"
                    )));
                }
                // z_clip = p22·z_view + p23 and w_clip = −z_view, so the stored
                // NDC depth is −p22 + p23 / Z for a view distance Z.
                let (p22, p23) = match (mode, far) {
                    (DepthMode::Standard, Some(f)) => (-(f + n) / (f - n), -2.0 * f * n / (f - n)),
                    (DepthMode::Standard, None) => (-1.0, -2.0 * n),
                    (DepthMode::ZeroToOne, Some(f)) => (-f / (f - n), -f * n / (f - n)),
                    (DepthMode::ZeroToOne, None) => (-1.0, -n),
                    (DepthMode::ReversedZ, Some(f)) => (n / (f - n), f * n / (f - n)),
                    (DepthMode::ReversedZ, None) => (0.0, n),
                };
                (p22, p23, fov_y)
            }
        };
        Ok((
            DepthProjection {
                p22,
                p23,
                zero_to_one: mode.zero_to_one(),
                clear_depth: mode.clear_depth(),
            },
            fov_y,
        ))
    }
}

#[cfg(feature = "glam")]
impl From<glam::Mat4> for Frame {
    fn from(m: glam::Mat4) -> Self {
        Frame::from_matrix(m.to_cols_array())
    }
}

#[cfg(feature = "glam")]
impl From<glam::DMat4> for Frame {
    fn from(m: glam::DMat4) -> Self {
        Frame::from_matrix(m.as_mat4().to_cols_array())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stored depth of view distance `z` under `mode`, from the
    /// projection's definition rather than the p22/p23 shortcut.
    fn stored_depth(mode: DepthMode, n: f64, far: Option<f64>, z: f64) -> f64 {
        // Fraction of the way from near to far in 1/z, the quantity
        // perspective depth is linear in: 0 at near, 1 at far (or infinity).
        let t = match far {
            Some(f) => (1.0 / n - 1.0 / z) / (1.0 / n - 1.0 / f),
            None => 1.0 - n / z,
        };
        match mode {
            DepthMode::Standard | DepthMode::ZeroToOne => t,
            DepthMode::ReversedZ => 1.0 - t,
        }
    }

    #[test]
    fn perspective_terms_linearise_every_depth_mode() {
        for mode in [
            DepthMode::Standard,
            DepthMode::ZeroToOne,
            DepthMode::ReversedZ,
        ] {
            for far in [Some(250.0f32), None] {
                let frame = Frame::perspective(0.8, 0.5, far).with_depth_mode(mode);
                let (p, fov) = frame.depth_terms().expect("valid");
                assert!((fov - 0.8).abs() < 1e-6);
                for z in [0.5, 1.0, 7.0, 100.0, 249.0] {
                    let d = stored_depth(mode, 0.5, far.map(f64::from), z);
                    let back = p.linearize(d);
                    assert!(
                        (back - z).abs() <= 1e-9 * z,
                        "{mode:?} {far:?} z {z}: {back}"
                    );
                }
                assert_eq!(p.clear_depth, mode.clear_depth());
            }
        }
    }

    #[test]
    fn a_matrix_gives_the_same_terms_as_its_parameters() {
        let (fov, n, f) = (0.9f32, 0.25f32, 80.0f32);
        let cot = 1.0 / (fov / 2.0).tan();
        let mut m = [0.0f32; 16];
        m[0] = cot / 1.5;
        m[5] = cot;
        m[10] = -(f + n) / (f - n);
        m[11] = -1.0;
        m[14] = -2.0 * f * n / (f - n);
        let (a, fov_a) = Frame::from_matrix(m).depth_terms().expect("valid");
        let (b, fov_b) = Frame::perspective(fov, n, Some(f))
            .depth_terms()
            .expect("valid");
        assert!((fov_a - fov_b).abs() < 1e-6);
        assert!((a.p22 - b.p22).abs() < 1e-6 && (a.p23 - b.p23).abs() < 1e-6);
    }

    #[test]
    fn orthographic_and_broken_projections_are_refused_in_one_line() {
        let mut ortho = [0.0f32; 16];
        ortho[0] = 1.0;
        ortho[5] = 1.0;
        ortho[10] = -0.01;
        ortho[15] = 1.0;
        for frame in [
            Frame::from_matrix(ortho),
            Frame::perspective(0.0, 0.1, Some(10.0)),
            Frame::perspective(1.0, 0.1, Some(0.05)),
            Frame::perspective(1.0, -1.0, None),
        ] {
            let e = frame.depth_terms().expect_err("refused").to_string();
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }
}
