//! Camera paths for the motion bench and `render --motion`: a
//! deterministic sequence of cameras around a scene's own camera, moving
//! at a stated mean image speed. Only the camera moves; geometry and
//! lights stay where they are (docs/motion.md).

use super::{Aabb, Camera};
use crate::{Error, Result};
use glam::{Mat4, Quat, Vec3, Vec4};
use std::fmt;
use std::str::FromStr;

/// How the camera moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Sideways along the camera's right axis, looking the same way.
    Pan,
    /// Around the vertical axis through the centre of the scene's bounds,
    /// at the camera's distance.
    Orbit,
    /// Along the view direction, towards the scene.
    Dolly,
}

impl PathKind {
    /// The name `--motion` spells it with.
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Pan => "pan",
            PathKind::Orbit => "orbit",
            PathKind::Dolly => "dolly",
        }
    }
}

/// A camera path as `--motion` gives it: `pan`, `orbit:frames=48,px=0.5`,
/// `dolly:frames=32`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionSpec {
    /// The kind of path.
    pub kind: PathKind,
    /// Frames along the path (at least 2).
    pub frames: u32,
    /// Mean image motion per frame of the scene's bounds, in pixels.
    pub px: f32,
}

impl MotionSpec {
    /// Frames when the spec names none.
    pub const DEFAULT_FRAMES: u32 = 24;
    /// Pixels per frame when the spec names none: sub-pixel, where
    /// crawling shows most.
    pub const DEFAULT_PX: f32 = 0.5;
    /// The longest path `--motion` takes.
    pub const MAX_FRAMES: u32 = 1000;
    /// The fastest speed `--motion` takes, pixels per frame.
    pub const MAX_PX: f32 = 64.0;
}

impl fmt::Display for MotionSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:frames={},px={}",
            self.kind.name(),
            self.frames,
            self.px
        )
    }
}

impl FromStr for MotionSpec {
    type Err = Error;

    fn from_str(s: &str) -> Result<MotionSpec> {
        let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
        let kind = match kind.trim() {
            "pan" => PathKind::Pan,
            "orbit" => PathKind::Orbit,
            "dolly" => PathKind::Dolly,
            other => {
                return Err(Error::invalid(format!(
                    "--motion `{s}`: unknown path `{other}` (pan, orbit or dolly)"
                )));
            }
        };
        let mut spec = MotionSpec {
            kind,
            frames: Self::DEFAULT_FRAMES,
            px: Self::DEFAULT_PX,
        };
        for option in rest.split(',').map(str::trim).filter(|o| !o.is_empty()) {
            let (key, value) = option.split_once('=').ok_or_else(|| {
                Error::invalid(format!(
                    "--motion `{s}`: `{option}` is not KEY=VALUE (frames=N, px=F)"
                ))
            })?;
            match key.trim() {
                "frames" => {
                    spec.frames = value
                        .trim()
                        .parse()
                        .ok()
                        .filter(|n| (2..=Self::MAX_FRAMES).contains(n))
                        .ok_or_else(|| {
                            Error::invalid(format!(
                                "--motion `{s}`: frames must be a whole number from 2 to {}",
                                Self::MAX_FRAMES
                            ))
                        })?;
                }
                "px" => {
                    spec.px = value
                        .trim()
                        .parse()
                        .ok()
                        .filter(|p: &f32| p.is_finite() && *p > 0.0 && *p <= Self::MAX_PX)
                        .ok_or_else(|| {
                            Error::invalid(format!(
                                "--motion `{s}`: px must be a number above 0 and at most {}",
                                Self::MAX_PX
                            ))
                        })?;
                }
                other => {
                    return Err(Error::invalid(format!(
                        "--motion `{s}`: unknown option `{other}` (frames=N, px=F)"
                    )));
                }
            }
        }
        Ok(spec)
    }
}

/// A path's cameras, one per frame; the scene's own camera is frame
/// [`CameraPath::middle`], `(frames − 1) / 2` rounded down.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// The spec it was made from.
    pub spec: MotionSpec,
    /// One camera per frame.
    pub cameras: Vec<Camera>,
    /// The path's step: world units (pan, dolly) or radians (orbit) per frame.
    pub step: f32,
}

impl CameraPath {
    /// The cameras of `spec` around `base` for a `width`×`height` image of
    /// a scene whose bounds are `bounds`: the step is chosen so that the
    /// mean image motion per frame of the bounds' corners and centre, over
    /// the whole path, is `spec.px`.
    pub fn new(
        spec: MotionSpec,
        base: &Camera,
        bounds: &Aabb,
        width: u32,
        height: u32,
    ) -> Result<CameraPath> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "a camera path needs an image of at least 1x1",
            ));
        }
        let points = gauge_points(bounds, base);
        // The speed of a small step first, then the step scaled until the
        // whole path's mean motion is the one asked for (the motion is not
        // linear in the step: perspective, rotation).
        let probe = match spec.kind {
            PathKind::Orbit => 1e-3,
            PathKind::Pan | PathKind::Dolly => 1e-3 * scale_of(bounds, base),
        };
        let probe_px = mean_motion(
            &cameras(spec.kind, base, bounds, probe, 2),
            &points,
            width,
            height,
        )
        .filter(|m| *m > 0.0)
        .ok_or_else(|| {
            Error::invalid(format!(
                "--motion {}: the scene's bounds do not move in the image along this path",
                spec.kind.name()
            ))
        })?;
        let mut step = probe * spec.px / probe_px;
        for _ in 0..4 {
            let path = cameras(spec.kind, base, bounds, step, spec.frames);
            match mean_motion(&path, &points, width, height) {
                Some(m) if m > 0.0 => step *= spec.px / m,
                _ => break,
            }
        }
        if spec.kind == PathKind::Dolly {
            let to_centre = (bounds.center() - base.position()).length();
            let travel = step * (spec.frames - 1 - CameraPath::middle(spec.frames) as u32) as f32;
            if !bounds.is_empty() && travel >= 0.5 * to_centre {
                return Err(Error::invalid(format!(
                    "--motion {spec}: the dolly would travel {travel:.3} of the camera's \
                     {to_centre:.3} to the scene's centre; ask for fewer frames or a lower px"
                )));
            }
        }
        let cameras = cameras(spec.kind, base, bounds, step, spec.frames);
        if cameras.iter().any(|c| !c.view.is_finite()) {
            return Err(Error::invalid(format!(
                "--motion {spec}: the path leaves finite numbers for this scene"
            )));
        }
        Ok(CameraPath {
            spec,
            cameras,
            step,
        })
    }

    /// The frame whose camera is the scene's own.
    pub fn middle(frames: u32) -> usize {
        (frames.max(1) as usize - 1) / 2
    }

    /// The mean image motion per frame of the bounds' corners and centre
    /// along this path, in pixels (`spec.px`, up to rounding).
    pub fn measured_px(&self, bounds: &Aabb, width: u32, height: u32) -> Option<f32> {
        let base = &self.cameras[CameraPath::middle(self.cameras.len() as u32)];
        mean_motion(&self.cameras, &gauge_points(bounds, base), width, height)
    }
}

/// A length the path's probe step is a small part of.
fn scale_of(bounds: &Aabb, base: &Camera) -> f32 {
    if !bounds.is_empty() && bounds.radius().is_finite() && bounds.radius() > 0.0 {
        bounds.radius()
    } else {
        base.near.max(1e-3)
    }
}

/// The points whose image motion is the path's speed: the bounds' corners
/// and centre (the camera's target, for bounds that are empty).
fn gauge_points(bounds: &Aabb, base: &Camera) -> Vec<Vec3> {
    if bounds.is_empty() {
        return vec![base.position() + base.forward() * scale_of(bounds, base)];
    }
    let mut points = bounds.corners().to_vec();
    points.push(bounds.center());
    points
}

/// `frames` cameras stepping `step` along `kind`, centred on `base`.
fn cameras(kind: PathKind, base: &Camera, bounds: &Aabb, step: f32, frames: u32) -> Vec<Camera> {
    let middle = CameraPath::middle(frames) as f32;
    let pivot = if bounds.is_empty() {
        base.position()
    } else {
        bounds.center()
    };
    (0..frames)
        .map(|k| {
            let s = (k as f32 - middle) * step;
            // The camera moves by `move_world` applied before its view: a
            // view matrix V becomes V · M⁻¹ for a world-space motion M.
            let motion = match kind {
                PathKind::Pan => {
                    let right = base.view.inverse().transform_vector3(Vec3::X);
                    Mat4::from_translation(right * s)
                }
                PathKind::Dolly => Mat4::from_translation(base.forward() * s),
                PathKind::Orbit => {
                    Mat4::from_translation(pivot)
                        * Mat4::from_quat(Quat::from_rotation_y(s))
                        * Mat4::from_translation(-pivot)
                }
            };
            Camera {
                view: base.view * motion.inverse(),
                ..*base
            }
        })
        .collect()
}

/// The mean over consecutive frames and over `points` of each point's
/// image motion in pixels; points behind the near plane in either frame
/// are left out. `None` when no point is seen in two frames.
fn mean_motion(cameras: &[Camera], points: &[Vec3], width: u32, height: u32) -> Option<f32> {
    let aspect = width as f32 / height as f32;
    let pixel = |c: &Camera, p: Vec3| {
        let clip = c.projection(aspect) * c.view * Vec4::new(p.x, p.y, p.z, 1.0);
        (clip.w > c.near * 0.5).then(|| {
            let ndc = clip.truncate() / clip.w;
            glam::Vec2::new(
                (ndc.x * 0.5 + 0.5) * width as f32,
                (ndc.y * 0.5 + 0.5) * height as f32,
            )
        })
    };
    let (mut sum, mut count) = (0.0f64, 0u32);
    for pair in cameras.windows(2) {
        for &p in points {
            if let (Some(a), Some(b)) = (pixel(&pair[0], p), pixel(&pair[1], p)) {
                sum += f64::from(a.distance(b));
                count += 1;
            }
        }
    }
    (count > 0).then(|| (sum / f64::from(count)) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> (Camera, Aabb) {
        let bounds = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.5, 1.0));
        (Camera::frame_bounds(&bounds, 0.8), bounds)
    }

    /// A point's pixel position, computed here from the camera's matrices
    /// without the module's helpers.
    fn project(c: &Camera, p: Vec3, w: f32, h: f32) -> glam::Vec2 {
        let clip = c.projection(w / h) * c.view * p.extend(1.0);
        glam::Vec2::new(
            (clip.x / clip.w * 0.5 + 0.5) * w,
            (clip.y / clip.w * 0.5 + 0.5) * h,
        )
    }

    #[test]
    fn specs_parse_with_their_defaults_and_refuse_nonsense_in_one_line() {
        let pan: MotionSpec = "pan".parse().unwrap();
        assert_eq!(
            pan,
            MotionSpec {
                kind: PathKind::Pan,
                frames: 24,
                px: 0.5
            }
        );
        let orbit: MotionSpec = "orbit:frames=48,px=0.25".parse().unwrap();
        assert_eq!(
            (orbit.kind, orbit.frames, orbit.px),
            (PathKind::Orbit, 48, 0.25)
        );
        assert_eq!(orbit.to_string().parse::<MotionSpec>().unwrap(), orbit);
        for bad in [
            "spin",
            "pan:frames=1",
            "pan:frames=x",
            "pan:px=0",
            "pan:px=-1",
            "pan:px=nan",
            "dolly:speed=3",
            "orbit:frames",
        ] {
            let e = bad.parse::<MotionSpec>().unwrap_err().to_string();
            assert!(e.contains(bad) && !e.contains('\n'), "{bad}: {e}");
        }
    }

    #[test]
    fn every_path_moves_the_bounds_at_the_asked_speed_around_the_scene_camera() {
        let (base, bounds) = scene();
        let (w, h) = (320u32, 180u32);
        for kind in [PathKind::Pan, PathKind::Orbit, PathKind::Dolly] {
            for px in [0.5f32, 2.0] {
                let spec = MotionSpec {
                    kind,
                    frames: 9,
                    px,
                };
                let path = CameraPath::new(spec, &base, &bounds, w, h).unwrap();
                assert_eq!(path.cameras.len(), 9);
                // The scene's own camera is the middle frame.
                let middle = path.cameras[CameraPath::middle(9)].view;
                assert!(middle.abs_diff_eq(base.view, 1e-5), "{kind:?}");
                // The speed, measured here with an independent projection.
                let mut points = bounds.corners().to_vec();
                points.push(bounds.center());
                let mut total = 0.0;
                for pair in path.cameras.windows(2) {
                    for &p in &points {
                        total += project(&pair[0], p, w as f32, h as f32)
                            .distance(project(&pair[1], p, w as f32, h as f32));
                    }
                }
                let mean = total / (8.0 * points.len() as f32);
                assert!((mean - px).abs() < 0.01 * px, "{kind:?} {px}: {mean}");
                // Only the camera moves: the lens stays.
                assert!(
                    path.cameras
                        .iter()
                        .all(|c| c.fov_y == base.fov_y && c.near == base.near && c.far == base.far)
                );
            }
        }
    }

    #[test]
    fn paths_move_as_named() {
        let (base, bounds) = scene();
        let spec = |kind| MotionSpec {
            kind,
            frames: 3,
            px: 4.0,
        };
        let pan = CameraPath::new(spec(PathKind::Pan), &base, &bounds, 320, 180).unwrap();
        let (a, b) = (pan.cameras[0], pan.cameras[2]);
        // Sideways: the same direction, the eye moved along the right axis.
        assert!(a.forward().abs_diff_eq(b.forward(), 1e-5));
        let right = base.view.inverse().transform_vector3(Vec3::X);
        let moved = b.position() - a.position();
        assert!(moved.normalize().abs_diff_eq(right, 1e-4));
        let dolly = CameraPath::new(spec(PathKind::Dolly), &base, &bounds, 320, 180).unwrap();
        let moved = dolly.cameras[2].position() - dolly.cameras[0].position();
        assert!(moved.normalize().abs_diff_eq(base.forward(), 1e-4));
        let orbit = CameraPath::new(spec(PathKind::Orbit), &base, &bounds, 320, 180).unwrap();
        // Around the bounds' centre: the distance to it and the height stay.
        let d = |c: &Camera| (c.position() - bounds.center()).length();
        assert!((d(&orbit.cameras[0]) - d(&base)).abs() < 1e-4);
        assert!((orbit.cameras[0].position().y - base.position().y).abs() < 1e-4);
        assert!(orbit.cameras[0].position().distance(base.position()) > 1e-4);
    }

    #[test]
    fn a_dolly_through_the_scene_is_refused() {
        let (base, bounds) = scene();
        let spec = MotionSpec {
            kind: PathKind::Dolly,
            frames: 1000,
            px: 64.0,
        };
        let e = CameraPath::new(spec, &base, &bounds, 320, 180)
            .unwrap_err()
            .to_string();
        assert!(e.contains("dolly would travel") && !e.contains('\n'), "{e}");
    }
}
