//! Per-sample goldens: built-in scenes rendered into the multisampled
//! G-buffer, EVERY sample of EVERY attachment and depth compared with
//! `tests/golden/*.samples.gz`, the resolved G-buffer too; and final images
//! compared by FLIP with `tests/golden/*.png`. See `tests/common/golden.rs`
//! for blessing (`DEFERRED_MSAA_BLESS=1`) and what a failure leaves behind.

mod common;

use common::golden::{FlipTolerance, Plane, SampleTolerance, check_image, check_samples};
use deferred_msaa_lab::gbuffer::GBufferLayout;
use deferred_msaa_lab::gl::{TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, SampleImage};
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer};
use deferred_msaa_lab::resolve::{ResolveRule, ResolveSettings};
use deferred_msaa_lab::scene::Scene;

const W: u32 = 64;
const H: u32 = 36;

/// Half-float storage is exact to 11 bits; a Mesa update may move a few edge
/// samples from one triangle to its neighbour, so up to 0.5% of the values
/// may differ by more.
const SAMPLES: SampleTolerance = SampleTolerance {
    abs: 2e-3,
    rel: 2e-3,
    outlier_fraction: 0.005,
};
/// Final images: what a rasteriser update may change, far below what a wrong
/// resolve (halos, lost edges) or a wrong light costs.
const FINAL: FlipTolerance = FlipTolerance {
    mean: 0.01,
    p99: 0.25,
};

fn plane(name: &str, img: &SampleImage, channels: usize) -> Plane {
    Plane {
        name: name.to_string(),
        shape: [
            img.samples as usize,
            img.height as usize,
            img.width as usize,
            channels,
        ],
        data: img
            .data
            .chunks_exact(4)
            .flat_map(|px| px[..channels].to_vec())
            .collect(),
    }
}

/// The layout the goldens were blessed with: the recommended one as it was
/// then, normals blended (`blend-normal`; the recommended layout now selects
/// them, see `GBufferLayout::recommended`), so they keep pinning that rule.
fn blessed_layout() -> GBufferLayout {
    let mut layout = GBufferLayout::recommended();
    let normal = layout.index_of("normal").expect("a normal attachment");
    layout.colors[normal].rule = ResolveRule::BlendNormal;
    layout
}

fn options(aa: AaMode, fxaa: bool) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa,
        fxaa,
        layout: blessed_layout(),
        // The goldens pin the full layout they were blessed with.
        adaptive: false,
        ..RenderOptions::default()
    }
}

fn per_sample_golden(scene_name: &str) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let scene = Scene::load(&format!("builtin:{scene_name}")).unwrap();
    let opts = options(AaMode::Resolve(ResolveSettings::default()), false);
    let mut renderer = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &opts).unwrap();
    renderer.render(gl).unwrap();
    let retrofit = renderer.retrofit().expect("multisampled");
    assert_eq!(retrofit.samples(), 4, "goldens are recorded at 4x");
    let (depth, colors, _) = retrofit.inputs().unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let mut planes = Vec::new();
    for (k, a) in opts.layout.colors.iter().enumerate() {
        let c = a.format.channels() as usize;
        planes.push(plane(
            &format!("{}_samples", a.name),
            &readback.read(gl, colors[k], 1).unwrap(),
            c,
        ));
        let resolved = readback
            .read(gl, TextureRef::from(&renderer.gbuffer().colors[k]), 1)
            .unwrap();
        planes.push(plane(&format!("{}_resolved", a.name), &resolved, c));
    }
    planes.push(plane(
        "depth_samples",
        &readback.read(gl, depth, 1).unwrap(),
        1,
    ));
    let resolved_depth = readback
        .read(gl, TextureRef::from(&renderer.gbuffer().depth), 1)
        .unwrap();
    planes.push(plane("depth_resolved", &resolved_depth, 1));
    // Every value must be finite: background keeps its clear values, no sentinels.
    for p in &planes {
        assert!(
            p.data.iter().all(|v| v.is_finite()),
            "{scene_name}: non-finite value in {}",
            p.name
        );
    }
    check_samples(&format!("{scene_name}-4x-median"), &planes, SAMPLES);
    readback.destroy(gl);
    renderer.destroy(gl);
    assert_eq!(live_objects(), before);
}

fn final_golden(scene_name: &str, label: &str, aa: AaMode, fxaa: bool) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load(&format!("builtin:{scene_name}")).unwrap();
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &options(aa, fxaa)).unwrap();
    renderer.render(gl).unwrap();
    let img = renderer.read_final(gl).unwrap();
    renderer.destroy(gl);
    check_image(&format!("{scene_name}-{label}"), &img, FINAL);
}

#[test]
fn greebles_samples() {
    per_sample_golden("greebles");
}

#[test]
fn thin_samples() {
    per_sample_golden("thin");
}

#[test]
fn zfight_samples() {
    per_sample_golden("zfight");
}

#[test]
fn emissive_samples() {
    per_sample_golden("emissive");
}

#[test]
fn greebles_final_images() {
    final_golden("greebles", "none", AaMode::None, false);
    final_golden(
        "greebles",
        "median",
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
    final_golden(
        "greebles",
        "median-fxaa",
        AaMode::Resolve(ResolveSettings::default()),
        true,
    );
}

#[test]
fn transparent_final_image() {
    final_golden(
        "transparent",
        "median",
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
}
