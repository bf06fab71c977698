//! The scene camera: a perspective camera with a world-to-view matrix.

use glam::{Mat4, Vec3, Vec4};

use super::Aabb;

/// A perspective camera. View space is right-handed, y up, looking down −z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// World to view (a rigid transform: rotation and translation only).
    pub view: Mat4,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Distance to the near plane (> 0).
    pub near: f32,
    /// Distance to the far plane; `None` for an infinite far plane.
    pub far: Option<f32>,
}

/// Horizontal room [`Camera::frame_bounds`] leaves: the box fits a view at
/// least this wide for its height, so 4:3, 16:9 and wider all see it whole.
const FRAME_MIN_ASPECT: f32 = 4.0 / 3.0;

/// Fraction of the half field of view the framed box may fill.
const FRAME_FILL: f32 = 0.9;

impl Camera {
    /// A camera at `eye` looking at `target`, world y up (any other up when
    /// looking straight up or down).
    pub fn look_at(eye: Vec3, target: Vec3, fov_y: f32, near: f32, far: Option<f32>) -> Camera {
        Camera {
            view: look_at(eye, target, Vec3::Y),
            fov_y,
            near,
            far,
        }
    }

    /// The standard OpenGL projection (clip z in −w..w, i.e. depth −1..1 in
    /// NDC) for this camera at the given width/height `aspect`; with
    /// `far == None` the limit as far → ∞ (depth reaches +1 only at infinity).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let f = 1.0 / (self.fov_y * 0.5).tan();
        let n = self.near;
        let (zz, zw) = match self.far {
            Some(far) => ((far + n) / (n - far), 2.0 * far * n / (n - far)),
            None => (-1.0, -2.0 * n),
        };
        Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, zz, -1.0),
            Vec4::new(0.0, 0.0, zw, 0.0),
        )
    }

    /// The camera's world-space position.
    pub fn position(&self) -> Vec3 {
        self.view.inverse().w_axis.truncate()
    }

    /// The world-space unit vector the camera looks along.
    pub fn forward(&self) -> Vec3 {
        self.view
            .inverse()
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or(Vec3::NEG_Z)
    }

    /// A camera that looks at `bounds` from a 3/4 angle (front-right, 25°
    /// above), as close as it can while the whole box stays inside the view
    /// (vertically within `fov_y`, horizontally for any aspect of 4:3 or
    /// wider), with the near and far planes fitted around the box.
    pub fn frame_bounds(bounds: &Aabb, fov_y: f32) -> Camera {
        Self::frame_points(bounds, bounds.corners(), fov_y)
    }

    /// Like [`Camera::frame_bounds`] (same direction, aimed at the centre of
    /// `bounds`), but fitted to `points` instead of the box's corners: a
    /// tighter frame when the points are the model's vertices, whose
    /// silhouette is usually well inside its box. See
    /// [`Scene::framing_camera`](super::Scene::framing_camera).
    pub fn frame_points(
        bounds: &Aabb,
        points: impl IntoIterator<Item = Vec3>,
        fov_y: f32,
    ) -> Camera {
        let fov_y = if fov_y.is_finite() && fov_y > 1e-4 && fov_y < 3.0 {
            fov_y
        } else {
            std::f32::consts::FRAC_PI_4
        };
        let usable = !bounds.is_empty() && bounds.radius().is_finite();
        let center = if usable { bounds.center() } else { Vec3::ZERO };
        // A flat or point-like model still gets some room around it.
        let pad = if usable {
            (bounds.radius() * 1e-3).max(1e-4)
        } else {
            0.5
        };

        let (azimuth, elevation) = (35f32.to_radians(), 25f32.to_radians());
        // From the centre towards the camera.
        let back = Vec3::new(
            azimuth.sin() * elevation.cos(),
            elevation.sin(),
            azimuth.cos() * elevation.cos(),
        );
        let right = Vec3::Y.cross(back).normalize();
        let up = back.cross(right);

        let t_y = (fov_y * 0.5).tan() * FRAME_FILL;
        let t_x = t_y * FRAME_MIN_ASPECT;
        let mut distance = 0.0f32;
        let (mut s_min, mut s_max) = (-pad, pad);
        let mut fit = |o: Vec3| {
            let s = o.dot(back);
            s_min = s_min.min(s - pad);
            s_max = s_max.max(s + pad);
            distance = distance
                .max(s + pad + (o.dot(up).abs() + pad) / t_y)
                .max(s + pad + (o.dot(right).abs() + pad) / t_x);
        };
        fit(Vec3::ZERO);
        for p in points {
            if p.is_finite() {
                fit(p - center);
            }
        }
        // Never inside the model, even when a point sits on the view axis.
        let extent = (s_max - s_min).max(1e-4);
        distance = distance.max(s_max + 0.05 * extent);

        let nearest = distance - s_max;
        let farthest = distance - s_min;
        let near = (nearest * 0.5).max(farthest * 1e-4);
        let far = farthest * 1.5 + near;
        let eye = center + back * distance;
        Camera {
            view: look_at(eye, center, Vec3::Y),
            fov_y,
            near,
            far: Some(far),
        }
    }
}

/// A right-handed world-to-view matrix: the camera at `eye` looks down its −z
/// towards `target`, with `up` (or another axis when `up` is parallel to the
/// view direction) pointing up the screen.
pub(crate) fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize_or(Vec3::NEG_Z);
    let mut s = f.cross(up);
    if s.length_squared() < 1e-12 {
        s = f.cross(Vec3::Z);
    }
    let s = s.normalize_or(Vec3::X);
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}
