//! Per-sample goldens: built-in scenes rendered into the multisampled
//! G-buffer, EVERY sample of EVERY attachment and depth compared with
//! `tests/golden/*.samples.gz`, the resolved G-buffer too; and final images
//! compared by FLIP with `tests/golden/*.png`. Each scene is pinned twice: in
//! the layout the first goldens were blessed with (`SCENE-4x-median`, normals
//! blended) and in the shipped recommended layout (`SCENE-recommended-...`,
//! normals selected), and the recommended layout again with two layers
//! (`SCENE-recommended-4x-median-layers2`: the second layer's resolved
//! attachments, depth and coverage too). See `tests/common/golden.rs` for blessing
//! (`DEFERRED_MSAA_BLESS=1 cargo test --test fast -- goldens::`), the `blessed on`
//! header and what a failure leaves behind.

use crate::common;

use common::golden::{
    FlipTolerance, Plane, SampleTolerance, check_image, check_samples, decode, driver, encode,
    encode_png, png_blessed_on,
};
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

/// Which layout a golden pins.
#[derive(Clone, Copy)]
enum Layout {
    /// [`blessed_layout`]: the first goldens' names, unchanged.
    Blessed,
    /// `GBufferLayout::recommended()` as shipped: FP32 position, D32F depth,
    /// normals selected; `recommended` in the golden's name.
    Recommended,
}

impl Layout {
    fn layout(self) -> GBufferLayout {
        match self {
            Layout::Blessed => blessed_layout(),
            Layout::Recommended => GBufferLayout::recommended(),
        }
    }

    /// The golden's name: `SCENE-REST` or `SCENE-recommended-REST`.
    fn name(self, scene_name: &str, rest: &str) -> String {
        match self {
            Layout::Blessed => format!("{scene_name}-{rest}"),
            Layout::Recommended => format!("{scene_name}-recommended-{rest}"),
        }
    }
}

fn options(layout: Layout, aa: AaMode, fxaa: bool) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa,
        fxaa,
        layout: layout.layout(),
        // The goldens pin the full layout; what the scene-adaptive plan
        // leaves out is `tests/plan.rs`'s to check.
        adaptive: false,
        ..RenderOptions::default()
    }
}

fn per_sample_golden(scene_name: &str, layout: Layout) {
    per_sample_golden_of(scene_name, layout, 1);
}

/// Every sample and the resolve of `layers` layers: with two, the second
/// layer's resolved attachments, its depth and its coverage too, pinned as
/// the first layer's are (`SCENE-…-4x-median-layers2`).
fn per_sample_golden_of(scene_name: &str, layout: Layout, layers: u32) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let scene = Scene::load(&format!("builtin:{scene_name}")).unwrap();
    let settings = ResolveSettings {
        layers,
        ..ResolveSettings::default()
    };
    let opts = options(layout, AaMode::Resolve(settings), false);
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
    if layers == 2 {
        let (second, second_depth) = retrofit.second_layer_gbuffer().expect("two layers");
        for (k, a) in opts.layout.colors.iter().enumerate() {
            let c = a.format.channels() as usize;
            let resolved = readback.read(gl, second[k], 1).unwrap();
            planes.push(plane(&format!("{}_layer2_resolved", a.name), &resolved, c));
        }
        let depth2 = readback.read(gl, second_depth, 1).unwrap();
        planes.push(plane("depth_layer2_resolved", &depth2, 1));
        let coverage = retrofit.second_layer_coverage().expect("two layers");
        let coverage = readback.read(gl, coverage, 1).unwrap();
        assert!(
            coverage.data.chunks_exact(4).any(|px| px[0] > 0.0),
            "{scene_name}: the second layer covers nothing, so its golden would pin nothing"
        );
        planes.push(plane("layer2_coverage", &coverage, 1));
    }
    // Every value must be finite: background keeps its clear values, no sentinels.
    for p in &planes {
        assert!(
            p.data.iter().all(|v| v.is_finite()),
            "{scene_name}: non-finite value in {}",
            p.name
        );
    }
    let label = if layers == 1 {
        "4x-median".to_string()
    } else {
        format!("4x-median-layers{layers}")
    };
    check_samples(
        &layout.name(scene_name, &label),
        &planes,
        SAMPLES,
        &driver(&ctx),
    );
    readback.destroy(gl);
    renderer.destroy(gl);
    assert_eq!(live_objects(), before);
}

fn final_golden(scene_name: &str, label: &str, layout: Layout, aa: AaMode, fxaa: bool) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load(&format!("builtin:{scene_name}")).unwrap();
    let opts = options(layout, aa, fxaa);
    let mut renderer = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &opts).unwrap();
    renderer.render(gl).unwrap();
    let img = renderer.read_final(gl).unwrap();
    renderer.destroy(gl);
    check_image(&layout.name(scene_name, label), &img, FINAL, &driver(&ctx));
}

fn final_images(scene_name: &str, layout: Layout) {
    final_golden(scene_name, "none", layout, AaMode::None, false);
    final_golden(
        scene_name,
        "median",
        layout,
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
    final_golden(
        scene_name,
        "median-fxaa",
        layout,
        AaMode::Resolve(ResolveSettings::default()),
        true,
    );
}

#[test]
fn greebles_samples() {
    per_sample_golden("greebles", Layout::Blessed);
}

#[test]
fn thin_samples() {
    per_sample_golden("thin", Layout::Blessed);
}

#[test]
fn zfight_samples() {
    per_sample_golden("zfight", Layout::Blessed);
}

#[test]
fn emissive_samples() {
    per_sample_golden("emissive", Layout::Blessed);
}

#[test]
fn greebles_final_images() {
    final_images("greebles", Layout::Blessed);
}

#[test]
fn transparent_final_image() {
    final_golden(
        "transparent",
        "median",
        Layout::Blessed,
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
}

// The shipped recommended layout: the same scenes, plus `hull`, the scene
// whose convex edges made the recommended layout select normals.

#[test]
fn recommended_greebles_samples() {
    per_sample_golden("greebles", Layout::Recommended);
}

#[test]
fn recommended_thin_samples() {
    per_sample_golden("thin", Layout::Recommended);
}

#[test]
fn recommended_zfight_samples() {
    per_sample_golden("zfight", Layout::Recommended);
}

#[test]
fn recommended_emissive_samples() {
    per_sample_golden("emissive", Layout::Recommended);
}

#[test]
fn recommended_hull_samples() {
    per_sample_golden("hull", Layout::Recommended);
}

#[test]
fn recommended_layout_selects_normals() {
    // What the recommended goldens stand for; if the layout changes, they
    // must be re-blessed knowingly.
    let layout = GBufferLayout::recommended();
    let normal = layout.index_of("normal").expect("a normal attachment");
    assert_eq!(layout.colors[normal].rule, ResolveRule::Select);
}

#[test]
fn recommended_greebles_final_images() {
    final_images("greebles", Layout::Recommended);
}

#[test]
fn recommended_hull_final_image() {
    final_golden(
        "hull",
        "median",
        Layout::Recommended,
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
}

#[test]
fn recommended_transparent_final_image() {
    final_golden(
        "transparent",
        "median",
        Layout::Recommended,
        AaMode::Resolve(ResolveSettings::default()),
        false,
    );
}

// The files' `blessed on` header, without GL.

const DRIVER: &str = "llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile) Mesa 22.3.6";

fn test_planes() -> Vec<Plane> {
    vec![
        Plane {
            name: "a".into(),
            shape: [2, 1, 2, 1],
            data: vec![0.0, 0.5, -1.0, 65504.0],
        },
        Plane {
            name: "b".into(),
            shape: [1, 1, 1, 3],
            data: vec![0.25, 1.0, 2.0],
        },
    ]
}

#[test]
fn sample_goldens_record_and_ignore_their_blesser() {
    let bytes = encode(&test_planes(), DRIVER);
    let first = bytes.split(|&b| b == b'\n').next().unwrap();
    assert_eq!(first, format!("blessed on: {DRIVER}").as_bytes());
    let (blessed_on, planes) = decode(&bytes);
    assert_eq!(blessed_on.as_deref(), Some(DRIVER));
    let read = |planes: &[Plane]| -> Vec<(String, [usize; 4], Vec<f32>)> {
        planes
            .iter()
            .map(|p| (p.name.clone(), p.shape, p.data.clone()))
            .collect()
    };
    assert_eq!(read(&planes), read(&test_planes()));
    // A file from before the header: the same bytes less its first line.
    let (blessed_on, planes) = decode(&bytes[first.len() + 1..]);
    assert_eq!(blessed_on, None);
    assert_eq!(read(&planes), read(&test_planes()));
    // A driver string never breaks the line structure.
    let (blessed_on, planes) = decode(&encode(&test_planes(), "odd\nrenderer\u{e9}"));
    assert_eq!(blessed_on.as_deref(), Some("odd renderer"));
    assert_eq!(read(&planes), read(&test_planes()));
}

#[test]
fn png_goldens_record_and_ignore_their_blesser() {
    let image = image::RgbaImage::from_fn(5, 3, |x, y| {
        image::Rgba([(x * 50) as u8, (y * 80) as u8, 7, 255])
    });
    let png = encode_png(&image, DRIVER);
    assert_eq!(png_blessed_on(&png).as_deref(), Some(DRIVER));
    let back = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
        .expect("the chunk keeps the PNG valid")
        .to_rgba8();
    assert_eq!(back, image);
    let mut plain = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut plain),
            image::ImageFormat::Png,
        )
        .unwrap();
    assert_eq!(png_blessed_on(&plain), None);
}

// Two layers in the recommended layout: the second layer's G-buffer, depth
// and coverage beside the first's, on the scenes with silhouettes against
// something behind them.

#[test]
fn recommended_greebles_two_layer_samples() {
    per_sample_golden_of("greebles", Layout::Recommended, 2);
}

#[test]
fn recommended_thin_two_layer_samples() {
    per_sample_golden_of("thin", Layout::Recommended, 2);
}

#[test]
fn recommended_hull_two_layer_samples() {
    per_sample_golden_of("hull", Layout::Recommended, 2);
}
