//! The timed jobs, one per (method entry, sample count), and the renderers
//! they share; what the still and the motion bench both time with.

use crate::context::HeadlessContext;
use crate::renderer::{AaMode, FrameTimings, RenderOptions, Renderer};
use crate::scene::Scene;
use crate::{Error, Result};
use image::RgbaImage;

use super::config::BenchConfig;
use super::methods::MethodEntry;
use super::report::ProfileStep;

/// One (entry, sample count) to time.
pub(super) struct Job<'a> {
    pub(super) entry: &'a MethodEntry,
    /// Hidden jobs are timed (as a lighting baseline) but not reported.
    pub(super) reported: bool,
    pub(super) samples_requested: u32,
    pub(super) options: RenderOptions,
    /// Index into the renderer pool.
    pub(super) slot: usize,
    pub(super) samples: u32,
    pub(super) frames: Vec<FrameTimings>,
    pub(super) image: Option<RgbaImage>,
    pub(super) gbuffer_bytes: u64,
    /// The fraction of pixels the method treated as complex in the last
    /// frame ([`Renderer::complex_pixel_fraction`]).
    pub(super) complex_fraction: Option<f64>,
    /// The share of pixels the second layer covers in the last frame.
    pub(super) second_layer_share: Option<f64>,
    /// `sparse`: the pixels that fell back to one sample in the last frame.
    pub(super) sparse_overflow_pixels: Option<u64>,
    /// With `--profile`: the retrofit's steps, median milliseconds each.
    pub(super) profile: Option<Vec<ProfileStep>>,
}

/// Renderers shared by jobs of the same class, FXAA setting, sample count
/// and layout (adaptive or full).
#[derive(Default)]
pub(super) struct Pool {
    pub(super) renderers: Vec<(PoolKey, Renderer)>,
}

/// A pool slot's method class, FXAA, SMAA, requested samples, adaptive layout and forward MSAA.
/// For a method whose frames build on the ones before (`taa`), its entry
/// too: it gets a renderer of its own, whose history no other entry's
/// `set_options` resets between its frames.
pub(super) type PoolKey = (
    &'static str,
    bool,
    bool,
    u32,
    (bool, bool, Option<String>),
    Option<String>,
);

impl Pool {
    pub(super) fn slot(
        &mut self,
        ctx: &HeadlessContext,
        scene: &Scene,
        key: PoolKey,
        options: &RenderOptions,
    ) -> Result<usize> {
        if let Some(i) = self.renderers.iter().position(|(k, _)| *k == key) {
            return Ok(i);
        }
        let mut renderer =
            Renderer::new(ctx.gl(), |name| ctx.get_proc_address(name), scene, options)?;
        // The bench reads the lit image alone, as a host whose passes after
        // lighting leave the G-buffer alone would: no first-layer restore.
        if let Err(e) = renderer.set_keep_gbuffer(ctx.gl(), false) {
            renderer.destroy(ctx.gl());
            return Err(e);
        }
        self.renderers.push((key, renderer));
        Ok(self.renderers.len() - 1)
    }

    pub(super) fn get(&mut self, slot: usize) -> Result<&mut Renderer> {
        self.renderers
            .get_mut(slot)
            .map(|(_, r)| r)
            .ok_or_else(|| Error::invalid("bench: a renderer slot is missing"))
    }

    pub(super) fn destroy(self, gl: &glow::Context) {
        for (_, r) in self.renderers {
            r.destroy(gl);
        }
    }
}

pub(super) fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

pub(super) fn render_options(
    config: &BenchConfig,
    aa: AaMode,
    fxaa: bool,
    samples: u32,
) -> RenderOptions {
    RenderOptions {
        width: config.width,
        height: config.height,
        samples,
        aa,
        fxaa,
        layout: config.layout.clone(),
        ..RenderOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(vec![]), 0.0);
    }
}
