//! The renderer's depth convention: standard GL depth or reversed-Z, the
//! projection for each, `glClipControl` around the frame, and the precision
//! check of a layout against the scene's depth range.

use crate::Result;
use crate::gbuffer::{DepthSetup, GBufferLayout, precision_warnings};
use crate::gl::Format;
use crate::scene::{Camera, Scene};
use glam::Mat4;
use glow::HasContext;
use std::ffi::c_void;

/// How the renderer maps view distance to the depth buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DepthMode {
    /// GL's default: depth −1..1 in NDC, near → 0, far → 1, cleared to 1.0,
    /// depth test `LESS`.
    Standard,
    /// Reversed-Z with `glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)`: near → 1,
    /// far (or infinity) → 0, cleared to 0.0, depth test `GREATER`. With a
    /// floating-point depth buffer the precision is nearly uniform in
    /// relative terms out to any distance. Needs OpenGL 4.5 or
    /// `GL_ARB_clip_control`.
    Reversed,
    /// [`DepthMode::Reversed`] when the context has `glClipControl` and the
    /// layout's depth format is floating point (`DEPTH_COMPONENT32F` or
    /// `DEPTH32F_STENCIL8`), else [`DepthMode::Standard`].
    #[default]
    Auto,
}

impl DepthMode {
    /// `standard`, `reversed` or `auto`.
    pub fn name(self) -> &'static str {
        match self {
            DepthMode::Standard => "standard",
            DepthMode::Reversed => "reversed",
            DepthMode::Auto => "auto",
        }
    }

    /// The mode a context with (`clip_control`) or without `glClipControl`
    /// uses for a depth buffer of `depth_format`: [`DepthMode::Auto`] is
    /// decided as documented, the others stay. `None` when
    /// [`DepthMode::Reversed`] is asked for without `glClipControl`.
    pub fn resolved(self, clip_control: bool, depth_format: Format) -> Option<DepthMode> {
        match self {
            DepthMode::Standard => Some(DepthMode::Standard),
            DepthMode::Reversed => clip_control.then_some(DepthMode::Reversed),
            DepthMode::Auto => {
                let float_depth =
                    matches!(depth_format, Format::Depth32f | Format::Depth32fStencil8);
                Some(if clip_control && float_depth {
                    DepthMode::Reversed
                } else {
                    DepthMode::Standard
                })
            }
        }
    }

    /// Whether this is reversed-Z.
    pub(crate) fn is_reversed(self) -> bool {
        self == DepthMode::Reversed
    }

    /// The depth the background keeps: 0.0 for reversed-Z, else 1.0.
    pub fn clear_depth(self) -> f32 {
        if self.is_reversed() { 0.0 } else { 1.0 }
    }

    /// The depth test that keeps the nearer fragment.
    pub(crate) fn nearer_func(self) -> u32 {
        if self.is_reversed() {
            glow::GREATER
        } else {
            glow::LESS
        }
    }
}

impl std::fmt::Display for DepthMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The camera's projection for `mode` at `aspect`: [`Camera::projection`]
/// for standard depth; for reversed-Z (clip z in 0..w with `GL_ZERO_TO_ONE`)
/// `p22 = n/(f−n)`, `p23 = f·n/(f−n)`, or `p22 = 0`, `p23 = n` with an
/// infinite far plane (computed in `f64`, then rounded).
pub(crate) fn projection(camera: &Camera, aspect: f32, mode: DepthMode) -> Mat4 {
    let mut m = camera.projection(aspect);
    if mode.is_reversed() {
        let n = f64::from(camera.near);
        let (p22, p23) = match camera.far {
            Some(far) => {
                let f = f64::from(far);
                (n / (f - n), f * n / (f - n))
            }
            None => (0.0, n),
        };
        m.z_axis.z = p22 as f32;
        m.w_axis.z = p23 as f32;
    }
    m
}

type ClipControlFn = unsafe extern "system" fn(origin: u32, depth: u32);

/// `glClipControl`, loaded through the host's loader (glow does not wrap it).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ClipControl {
    f: Option<ClipControlFn>,
}

/// GL state a frame changes for its depth convention, as the host had it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SavedDepthState {
    clip: Option<(u32, u32)>,
    depth_func: u32,
    clear_depth: f32,
}

impl ClipControl {
    /// Load `glClipControl` when the context has it (`available`: OpenGL 4.5
    /// or `GL_ARB_clip_control`, see [`crate::gl::Capabilities`]); loaders
    /// hand out stubs for any name, so the pointer alone proves nothing.
    pub(crate) fn load(loader: &dyn Fn(&str) -> *const c_void, available: bool) -> Self {
        if !available {
            return ClipControl::default();
        }
        let p = loader("glClipControl");
        // SAFETY: a non-null pointer the context's loader returns for
        // `glClipControl`, which the context implements, has its signature.
        let f = (!p.is_null())
            .then(|| unsafe { std::mem::transmute::<*const c_void, ClipControlFn>(p) });
        ClipControl { f }
    }

    /// Whether `glClipControl` can be called.
    pub(crate) fn available(&self) -> bool {
        self.f.is_some()
    }

    fn set(&self, origin: u32, depth: u32) {
        if let Some(f) = self.f {
            // SAFETY: loaded for the current context; valid enums.
            unsafe { f(origin, depth) };
        }
    }

    /// Save the host's clip control, depth function and clear depth, then set
    /// the clip control `mode` needs (`GL_LOWER_LEFT` and `GL_ZERO_TO_ONE`
    /// for reversed-Z, GL's default otherwise, whatever the host had).
    pub(crate) fn enter(&self, gl: &glow::Context, mode: DepthMode) -> SavedDepthState {
        let saved = unsafe {
            SavedDepthState {
                clip: self.available().then(|| {
                    (
                        gl.get_parameter_i32(glow::CLIP_ORIGIN) as u32,
                        gl.get_parameter_i32(glow::CLIP_DEPTH_MODE) as u32,
                    )
                }),
                depth_func: gl.get_parameter_i32(glow::DEPTH_FUNC) as u32,
                clear_depth: gl.get_parameter_f32(glow::DEPTH_CLEAR_VALUE),
            }
        };
        let depth = if mode.is_reversed() {
            glow::ZERO_TO_ONE
        } else {
            glow::NEGATIVE_ONE_TO_ONE
        };
        if saved.clip != Some((glow::LOWER_LEFT, depth)) {
            self.set(glow::LOWER_LEFT, depth);
        }
        saved
    }

    /// Put back what [`ClipControl::enter`] saved.
    pub(crate) fn leave(&self, gl: &glow::Context, saved: SavedDepthState) {
        if let Some((origin, depth)) = saved.clip {
            self.set(origin, depth);
        }
        unsafe {
            gl.depth_func(saved.depth_func);
            gl.clear_depth_f64(f64::from(saved.clear_depth));
        }
    }
}

/// How far the scene reaches from the camera, and the size of its detail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SceneExtent {
    /// The farthest corner of the scene's bounds, in view distance.
    pub(crate) max_distance: f64,
    /// The smallest depth difference that should stay resolvable: 1/1000 of
    /// the bounds' radius.
    pub(crate) detail: f64,
}

impl SceneExtent {
    /// The extent of `scene` as its camera sees it; `None` for an empty or
    /// non-finite scene (nothing to check).
    pub(crate) fn of(scene: &Scene) -> Option<Self> {
        if scene.bounds.is_empty() {
            return None;
        }
        let view = scene.camera.view.as_dmat4();
        let max_distance = scene
            .bounds
            .corners()
            .iter()
            .map(|c| -view.transform_point3(c.as_dvec3()).z)
            .fold(f64::NEG_INFINITY, f64::max);
        let radius = (scene.bounds.max.as_dvec3() - scene.bounds.min.as_dvec3()).length() * 0.5;
        let detail = radius * 1e-3;
        let ok = max_distance.is_finite() && detail.is_finite() && detail > 0.0;
        // Behind the camera entirely: nothing is drawn.
        (ok && max_distance > 0.0).then_some(SceneExtent {
            max_distance,
            detail,
        })
    }
}

/// The precision warnings for drawing `extent` with `camera` into `layout`
/// in `mode` (see [`precision_warnings`]).
pub(crate) fn warnings(
    layout: &GBufferLayout,
    camera: &Camera,
    mode: DepthMode,
    extent: Option<SceneExtent>,
) -> Vec<String> {
    let Some(extent) = extent else {
        return Vec::new();
    };
    let setup = DepthSetup {
        near: f64::from(camera.near),
        far: camera.far.map(f64::from),
        reversed: mode.is_reversed(),
    };
    let max_distance = extent.max_distance.max(setup.near);
    precision_warnings(layout, &setup, max_distance, extent.detail)
}

/// Decide `requested` for this context and layout.
pub(crate) fn resolve_mode(
    gl: &glow::Context,
    requested: DepthMode,
    clip: &ClipControl,
    depth_format: Format,
) -> Result<DepthMode> {
    requested
        .resolved(clip.available(), depth_format)
        .ok_or_else(|| {
            let v = gl.version();
            deferred_msaa::Error::Unsupported {
                feature: "reversed-Z depth (DepthMode::Reversed)".into(),
                requires: "glClipControl (OpenGL 4.5 or GL_ARB_clip_control)".into(),
                found: format!("OpenGL {}.{}", v.major, v.minor),
            }
            .into()
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_picks_reversed_only_with_clip_control_and_float_depth() {
        let auto = DepthMode::Auto;
        assert_eq!(
            auto.resolved(true, Format::Depth32f),
            Some(DepthMode::Reversed)
        );
        assert_eq!(
            auto.resolved(true, Format::Depth32fStencil8),
            Some(DepthMode::Reversed)
        );
        assert_eq!(
            auto.resolved(true, Format::Depth24),
            Some(DepthMode::Standard)
        );
        assert_eq!(
            auto.resolved(false, Format::Depth32f),
            Some(DepthMode::Standard)
        );
        assert_eq!(DepthMode::Reversed.resolved(false, Format::Depth32f), None);
        assert_eq!(
            DepthMode::Reversed.resolved(true, Format::Depth24),
            Some(DepthMode::Reversed)
        );
        assert_eq!(DepthMode::default(), DepthMode::Auto);
    }

    #[test]
    fn reversed_projection_maps_near_to_one_and_far_to_zero() {
        let depth = |m: &Mat4, z: f32| {
            let c = *m * glam::Vec4::new(0.0, 0.0, -z, 1.0);
            c.z / c.w
        };
        let finite = Camera {
            view: Mat4::IDENTITY,
            fov_y: 0.8,
            near: 0.5,
            far: Some(100.0),
        };
        let m = projection(&finite, 1.5, DepthMode::Reversed);
        assert!((depth(&m, 0.5) - 1.0).abs() < 1e-6);
        assert!(depth(&m, 100.0).abs() < 1e-6);
        let infinite = Camera {
            far: None,
            ..finite
        };
        let m = projection(&infinite, 1.5, DepthMode::Reversed);
        assert!((depth(&m, 0.5) - 1.0).abs() < 1e-6);
        assert!((depth(&m, 5.0e5) - 1.0e-6).abs() < 1e-12);
        assert_eq!(
            projection(&finite, 1.5, DepthMode::Standard),
            finite.projection(1.5)
        );
    }
}
