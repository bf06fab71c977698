//! The per-scene pixel masks each run's FLIP is split by: the pixels
//! holding two or more surface clusters, and those holding three or more.

use crate::Result;
use crate::context::HeadlessContext;
use crate::renderer::{AaMode, Renderer};
use crate::resolve::{ResolveMethod, ResolveSettings};
use crate::scene::Scene;
use image::GrayImage;

use super::config::BenchConfig;
use super::pool::render_options;

/// The pixels of `scene` at the bench's size that hold two or more surface
/// clusters (silhouettes, creases), and those that hold three or more, 255
/// where marked and 0 elsewhere: the masks each run's FLIP is split by
/// (`flip_edges` over the first, `flip_interior` over the rest,
/// `flip_three_clusters` over the second), made once per scene and shared
/// by all its runs. Both come from one frame of `median:layers=2` (clusters
/// by depth window and normal) at the first requested sample count: two or
/// more where the second layer covers any of the pixel; three or more where
/// the resolve's CPU reference, over the frame's samples read back, finds
/// samples of neither kept cluster (its `joined`: the resolve's own
/// clusters, by depth window and normal test). `None` when that count gives no
/// multisampling.
pub(super) fn cluster_masks(
    ctx: &HeadlessContext,
    config: &BenchConfig,
    scene: &Scene,
) -> Result<Option<(GrayImage, GrayImage)>> {
    let gl = ctx.gl();
    let two_layers = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        layers: 2,
        ..ResolveSettings::default()
    });
    let samples = config.samples.first().copied().unwrap_or(1);
    let options = render_options(config, two_layers, false, samples);
    let mut renderer = Renderer::new(gl, |name| ctx.get_proc_address(name), scene, &options)?;
    let masks = (|| {
        renderer.render(gl)?;
        let Some(coverage) = renderer.read_second_layer_coverage(gl)? else {
            return Ok(None);
        };
        let Some(retrofit) = renderer.retrofit() else {
            return Ok(None);
        };
        let cpu = retrofit.cpu_reference(&renderer.resolve_frame())?;
        let (depth, colors, _) = retrofit.inputs()?;
        let mut readback = crate::readback::Readback::new(gl)?;
        let read = (|| {
            let colors = colors
                .iter()
                .map(|t| readback.read(gl, *t, 1))
                .collect::<deferred_msaa::Result<Vec<_>>>()?;
            Ok::<_, deferred_msaa::Error>((colors, readback.read(gl, depth, 1)?))
        })();
        readback.destroy(gl);
        let (colors, depth) = read?;
        let three = GrayImage::from_fn(depth.width, depth.height, |x, y| {
            let px = crate::readback::pixel_samples(&depth, &colors, x, y);
            // Samples of neither kept cluster, each joined to one of them.
            let at = crate::resolve::cpu::PixelPlace {
                x,
                y,
                width: depth.width,
                height: depth.height,
            };
            let joined = cpu.resolve_second_layer_at(&px, Some(at)).joined;
            image::Luma([if joined[0] + joined[1] > 0 { 255 } else { 0 }])
        });
        // Two clusters or more: the second layer covers some of the pixel.
        let mut two = coverage;
        two.pixels_mut()
            .for_each(|p| p[0] = if p[0] > 0 { 255 } else { 0 });
        Ok(Some((two, three)))
    })();
    renderer.destroy(gl);
    masks
}
