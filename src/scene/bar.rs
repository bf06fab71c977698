//! Thin bars a scene declares so that the bench can measure how wide each
//! method draws them ([`crate::bench::bar_width`]): the stretch of each bar
//! to measure along, in world space, and its projection into an image.

use glam::{DVec2, Vec3};

use super::Camera;

/// A straight bar of constant width, flat and facing the camera, whose
/// drawn width is measured along the stretch of its centreline from
/// [`Bar::from`] to [`Bar::to`]. The scene keeps that stretch away from the
/// bar's ends and keeps other geometry out of the image around it, so that
/// across the bar an image shows the bar and the one surface behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bar {
    /// World-space start of the measured stretch of the centreline.
    pub from: Vec3,
    /// World-space end of the measured stretch of the centreline.
    pub to: Vec3,
    /// World-space vector from the centreline to one long edge: half the
    /// bar's width, perpendicular to the centreline, in the bar's plane.
    pub half_width: Vec3,
}

/// A [`Bar`] as an image of a given size shows it, in pixels: x to the
/// right, y down, (0, 0) the top-left corner of the top-left pixel (so that
/// pixel's centre is (0.5, 0.5)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageBar {
    /// Where the measured stretch of the centreline starts.
    pub from: DVec2,
    /// Where it ends.
    pub to: DVec2,
    /// The bar's width across its centreline, in pixels.
    pub width: f64,
}

impl Bar {
    /// The bar in a `width`×`height` image rendered from `camera`; `None`
    /// when a point of it is not in front of the camera, or the image or
    /// the measured stretch is empty.
    pub fn in_image(&self, camera: &Camera, width: u32, height: u32) -> Option<ImageBar> {
        if width == 0 || height == 0 {
            return None;
        }
        let (w, h) = (f64::from(width), f64::from(height));
        let clip_from_world = camera.projection((w / h) as f32) * camera.view;
        let pixel = |p: Vec3| {
            let clip = clip_from_world * p.extend(1.0);
            if clip.w.is_nan() || clip.w <= 0.0 {
                return None;
            }
            let (x, y) = (f64::from(clip.x / clip.w), f64::from(clip.y / clip.w));
            Some(DVec2::new((x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h))
        };
        let (from, to) = (pixel(self.from)?, pixel(self.to)?);
        let along = (to - from).try_normalize()?;
        // The distance between the projected long edges, across the
        // projected centreline, at both ends of the stretch: equal for a bar
        // square to the view, nearly so for one at an angle to it.
        let across = |at: Vec3| -> Option<f64> {
            let edges = pixel(at + self.half_width)? - pixel(at - self.half_width)?;
            Some(along.perp_dot(edges).abs())
        };
        let width = 0.5 * (across(self.from)? + across(self.to)?);
        Some(ImageBar { from, to, width })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bar square to the view, straight ahead, projects where the
    /// pinhole model says: its width is its world width times the pixels
    /// per unit at its distance, and its centre is the image's centre.
    #[test]
    fn a_bar_facing_the_camera_projects_to_its_pixel_width() {
        let fov_y = 30f32.to_radians();
        let camera = Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, fov_y, 0.1, None);
        let bar = Bar {
            from: Vec3::new(0.0, -1.0, 0.0),
            to: Vec3::new(0.0, 1.0, 0.0),
            half_width: Vec3::new(0.02, 0.0, 0.0),
        };
        let image = bar.in_image(&camera, 640, 360).expect("in view");
        let pixels_per_unit = 360.0 / (2.0 * 10.0 * f64::from(fov_y * 0.5).tan());
        assert!(
            (image.width - 0.04 * pixels_per_unit).abs() < 1e-3,
            "{image:?}"
        );
        let centre = (image.from + image.to) * 0.5;
        assert!(
            (centre - DVec2::new(320.0, 180.0)).length() < 1e-3,
            "{image:?}"
        );
        // y grows downwards: the bar's world bottom is the image's lower end.
        assert!(image.from.y > image.to.y, "{image:?}");

        let behind = Bar {
            from: Vec3::new(0.0, 0.0, 20.0),
            ..bar
        };
        assert_eq!(behind.in_image(&camera, 640, 360), None);
        assert_eq!(bar.in_image(&camera, 0, 360), None);
    }
}
