//! What to benchmark ([`BenchConfig`]), checked before anything renders,
//! and the point lights it adds to each scene.

use crate::context::Backend;
use crate::gbuffer::GBufferLayout;
use crate::scene::{Aabb, Light, MotionSpec, Scene};
use crate::{Error, Result};
use glam::Vec3;
use std::path::Path;

use super::methods::{MethodEntry, default_methods};

/// The scenes benchmarked when none is named: the two the report's claims
/// are about, `hull` (detail inside a model, where the depth-aware resolve
/// blends) and `halo` (the paper's Figure 4, where averaging lights the gap
/// behind an edge).
pub const DEFAULT_SCENES: &[&str] = &["builtin:hull", "builtin:halo"];

/// The reference renders at this many times the width and the height.
pub const REFERENCE_SCALE: u32 = 4;

/// The luminance excess over the reference that makes a halo pixel.
pub const HALO_THRESHOLD: f32 = 0.1;

/// What to benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchConfig {
    /// The context backend.
    pub backend: Backend,
    /// Scene specs: `builtin:NAME` or `.gltf`/`.glb` paths.
    pub scenes: Vec<String>,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Requested sample counts for the multisampled methods (each is run at
    /// every count; `none` runs once, at 1).
    pub samples: Vec<u32>,
    /// The method entries, in report order.
    pub methods: Vec<MethodEntry>,
    /// Point lights to add to each scene ([`extra_lights`]).
    pub lights: u32,
    /// Timed frames per run (the median is reported); at least 1.
    pub frames: u32,
    /// Untimed rounds before them.
    pub warmup: u32,
    /// The G-buffer layout.
    pub layout: GBufferLayout,
    /// Show a progress bar on stderr (drawn only when stderr is a terminal).
    pub progress: bool,
    /// After the timed frames, render `frames` more of each method that
    /// resolves with the retrofit profiling its steps (`glFinish` around
    /// each), and report each step's median ([`Run::profile`](super::report::Run::profile)).
    pub profile: bool,
    /// Render a camera path instead of still frames (`--motion`): every
    /// method renders each of its frames, measured against the reference
    /// of every frame ([`Run::motion`](super::report::Run::motion)); `frames` does not apply.
    pub motion: Option<MotionSpec>,
}

impl Default for BenchConfig {
    /// The default scenes and methods at 640×360, 4x, 9 frames after 3
    /// warm-up rounds, no extra lights, the recommended layout, EGL.
    fn default() -> Self {
        BenchConfig {
            backend: Backend::Egl,
            scenes: DEFAULT_SCENES.iter().map(|s| s.to_string()).collect(),
            width: 640,
            height: 360,
            samples: vec![4],
            methods: default_methods(),
            lights: 0,
            frames: 9,
            warmup: 3,
            layout: GBufferLayout::recommended(),
            progress: false,
            profile: false,
            motion: None,
        }
    }
}

impl BenchConfig {
    /// Check everything that can be checked without a context: sizes,
    /// counts, and that every scene names a built-in or an existing file.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(format!(
                "the image size must be at least 1x1, got {}x{}",
                self.width, self.height
            )));
        }
        if self.scenes.is_empty() {
            return Err(Error::invalid("bench needs at least one scene"));
        }
        if self.methods.is_empty() {
            return Err(Error::invalid("bench needs at least one method"));
        }
        if self.samples.is_empty() || self.samples.contains(&0) {
            return Err(Error::invalid(
                "--samples must be at least 1 (use the `none` method for no multisampling)",
            ));
        }
        if self.frames == 0 {
            return Err(Error::invalid("--frames must be at least 1"));
        }
        for spec in &self.scenes {
            check_scene_spec(spec)?;
        }
        Ok(self.layout.validate()?)
    }
}

/// Fail early on a scene spec that cannot load: an unknown built-in or a
/// missing file (parse errors surface when the scene is loaded).
fn check_scene_spec(spec: &str) -> Result<()> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        if !Scene::builtin_names().contains(&name) {
            return Err(Error::Scene {
                path: spec.into(),
                reason: format!(
                    "no built-in scene named `{name}`; the built-ins are {}",
                    Scene::builtin_names().join(", ")
                ),
            });
        }
        return Ok(());
    }
    if !Path::new(spec).is_file() {
        let hint = if Scene::builtin_names().contains(&spec) {
            format!("; did you mean `builtin:{spec}`?")
        } else {
            String::new()
        };
        return Err(Error::Scene {
            path: spec.into(),
            reason: format!("no such file{hint}"),
        });
    }
    Ok(())
}

/// Parse `WIDTHxHEIGHT` (both at least 1).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = |why: &str| {
        Error::invalid(format!(
            "`{s}` is not a size: {why} (expected WIDTHxHEIGHT, e.g. 640x360)"
        ))
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| bad("no `x`"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| bad("the width is not a number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| bad("the height is not a number"))?;
    if w == 0 || h == 0 {
        return Err(bad("width and height must be at least 1"));
    }
    Ok((w, h))
}

/// `n` point lights placed deterministically around `bounds`: on a
/// Fibonacci sphere of 1.25 times the bounding radius about its centre,
/// with colours cycling through a small palette, a range of 4 radii, and
/// intensities that together add about as much light as two of the default
/// rig's point lights (so the image stays exposed while the lighting cost
/// grows with `n`).
pub fn extra_lights(bounds: &Aabb, n: u32) -> Vec<Light> {
    if n == 0 {
        return Vec::new();
    }
    let c = bounds.center();
    let r = bounds.radius().max(1e-3);
    let total = 2.0 * (1.6 * r) * (1.6 * r) * 1.2;
    let each = total / n as f32;
    let palette = [
        Vec3::new(1.0, 0.85, 0.7),
        Vec3::new(0.7, 0.85, 1.0),
        Vec3::new(1.0, 0.7, 0.85),
        Vec3::new(0.8, 1.0, 0.75),
    ];
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let ring = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * i as f32;
            let dir = Vec3::new(ring * phi.cos(), y, ring * phi.sin());
            Light::point(
                c + dir * 1.25 * r,
                palette[i as usize % palette.len()],
                each,
                Some(4.0 * r),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("640x360").unwrap(), (640, 360));
        assert_eq!(parse_size("96X54").unwrap(), (96, 54));
        for bad in ["0x10", "big", "10x", "x10", "-1x5"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn extra_lights_are_deterministic_and_around_the_bounds() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let a = extra_lights(&b, 10);
        assert_eq!(a, extra_lights(&b, 10));
        assert_eq!(a.len(), 10);
        for l in &a {
            let d = (l.position - b.center()).length();
            assert!((d - 1.25 * b.radius()).abs() < 1e-3);
        }
        assert!(extra_lights(&b, 0).is_empty());
    }
}
