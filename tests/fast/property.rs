//! The property test's fast share: a few hundred random host G-buffers
//! (`tests/common/property.rs` says what each is put through; the slow
//! tier runs more than a thousand), and the named regression cases its
//! failures shrank to, each with its layout written out.

use crate::common;
use crate::common::property::{Verdict, check, run_seeds};

/// Seeds of the fast tier.
const SEEDS: std::ops::Range<u64> = 0..300;

#[test]
fn random_hosts_retrofit_or_refuse_in_one_line() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let limits = deferred_msaa_testkit::random_host::Limits::of(ctx.gl());
    let summary = run_seeds(&ctx, SEEDS, "--test fast property::random_hosts --");
    eprintln!("{}", summary.report(ctx.gl(), limits));
    assert!(
        summary.failures.is_empty(),
        "{} of the random hosts failed (seeds {:?}); each is printed above with its replay command",
        summary.failures.len(),
        summary.failures.iter().map(|f| f.0).collect::<Vec<_>>()
    );
    let live = deferred_msaa::gl::live_objects();
    assert_eq!(live.total(), 0, "the crate's GL objects left: {live:?}");
    assert!(summary.retrofitted > 0, "no random host was retrofitted");
}

use deferred_msaa::RetrofitOptions;
use deferred_msaa_testkit::random_host::{
    ColorSpec, DepthPoint, DepthSpec, HostFormat, HostSpec, Limits, Storage,
};

/// A host written out: the seed its faces' values and triangle are drawn
/// from, colour points with their format, upload type and image kind,
/// every one drawn in order, and the depth.
fn written_out(
    seed: u64,
    size: (u32, u32),
    colors: &[(u32, &str, &str, Storage)],
    depth: Option<(&str, &str, Storage, DepthPoint)>,
    options: RetrofitOptions,
) -> HostSpec {
    HostSpec {
        seed,
        width: size.0,
        height: size.1,
        resized: size,
        colors: colors
            .iter()
            .map(|&(point, name, ty, storage)| ColorSpec {
                point,
                format: HostFormat::of(name, ty),
                storage,
                size: None,
            })
            .collect(),
        draw_buffers: colors.iter().map(|c| Some(c.0)).collect(),
        depth: depth.map(|(name, ty, storage, point)| DepthSpec {
            format: HostFormat::of(name, ty),
            storage,
            point,
        }),
        other_options: options.clone(),
        options,
    }
}

/// Found by the property test: a host that draws into every colour point
/// the context has, with a depth-stencil attachment, left the stencil
/// copy's reference index no point of its own; the retrofit attached it
/// past `GL_MAX_COLOR_ATTACHMENTS` and failed with a GL error. It is now
/// refused in one line naming the depth-stencil point.
#[test]
fn every_colour_point_and_a_stencil_is_refused_in_one_line() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let max = Limits::of(ctx.gl()).color_attachments;
    let colors: Vec<(u32, &str, &str, Storage)> = (0..max)
        .map(|n| (n, "GL_RGBA8", "GL_UNSIGNED_BYTE", Storage::Texture))
        .collect();
    let spec = written_out(
        0,
        (16, 8),
        &colors,
        Some((
            "GL_DEPTH24_STENCIL8",
            "GL_UNSIGNED_INT_24_8",
            Storage::Renderbuffer,
            DepthPoint::DepthStencil,
        )),
        RetrofitOptions::default(),
    );
    assert_eq!(
        check(&ctx, &spec),
        Verdict::Refused("no draw buffer for the stencil copy".into())
    );
    // One colour fewer leaves the point the stencil copy needs.
    let spec = written_out(
        0,
        (16, 8),
        &colors[1..],
        spec.depth.as_ref().map(|_| {
            (
                "GL_DEPTH24_STENCIL8",
                "GL_UNSIGNED_INT_24_8",
                Storage::Renderbuffer,
                DepthPoint::DepthStencil,
            )
        }),
        RetrofitOptions::default(),
    );
    assert_eq!(check(&ctx, &spec), Verdict::Retrofitted);
}

/// Found by the property test (seed 9, shrunk): a `blend-normal` rule on
/// an attachment whose face value is not unit length (normals scaled by a
/// gloss, or anything else) renormalised it even where every sample is
/// the same face, so the host's texel changed by a step inside faces. Equal
/// samples now resolve to themselves under every rule. (The case was an
/// RGBA8 attachment, where `blend-normal` is now refused; the same on a
/// half-float one.)
#[test]
fn equal_samples_keep_an_unnormalised_normal_as_written() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let mut options = RetrofitOptions {
        rules: vec![(
            deferred_msaa::ColorAttachment(6),
            deferred_msaa::resolve::ResolveRule::BlendNormal,
        )],
        ..RetrofitOptions::default()
    };
    options.resolve.fast_path = false;
    let spec = written_out(
        9,
        (1, 8),
        &[
            (0, "GL_RGBA8", "GL_UNSIGNED_BYTE", Storage::Texture),
            (6, "GL_RGBA16F", "GL_FLOAT", Storage::Texture),
        ],
        Some((
            "GL_DEPTH_COMPONENT",
            "GL_FLOAT",
            Storage::Texture,
            DepthPoint::Depth,
        )),
        options,
    );
    assert_eq!(check(&ctx, &spec), Verdict::Retrofitted);
}

/// Found by the property test (seed 721 of the slow tier, shrunk): a
/// position attachment whose key is at or behind the eye (an RGBA8 world
/// position, z in [0, 1]) gave equal samples no window, so with two
/// layers a one-surface pixel got a second cluster and the mix changed
/// the lit pixel. Equal keys are now one surface whatever their sign.
#[test]
fn equal_keys_behind_the_eye_are_one_surface_with_two_layers() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let mut options = RetrofitOptions {
        position_attachment: Some(deferred_msaa::ColorAttachment(0)),
        position_space: deferred_msaa::PositionSpace::World,
        ..RetrofitOptions::default()
    };
    options.resolve.method = deferred_msaa::resolve::ResolveMethod::Back;
    options.resolve.window = deferred_msaa::resolve::Window::Hard;
    options.resolve.fast_path = false;
    options.resolve.layers = 2;
    let spec = written_out(
        721,
        (1, 13),
        &[(0, "GL_RGBA8", "GL_UNSIGNED_BYTE", Storage::Texture)],
        Some((
            "GL_DEPTH_COMPONENT32",
            "GL_UNSIGNED_INT",
            Storage::Texture,
            DepthPoint::Depth,
        )),
        options,
    );
    assert_eq!(check(&ctx, &spec), Verdict::Retrofitted);
}
