//! What a run measures: how many pixels are complex, the statistics of
//! the times, and the methods timed.

use crate::common::quantile;
use deferred_msaa_lab::readback::{Readback, pixel_samples};
use deferred_msaa_lab::resolve::cpu::{CpuCamera, CpuKeySource, CpuResolve, PixelPlace};
use deferred_msaa_lab::resolve::{KeySource, ResolveParams};
use deferred_msaa_lab::retrofit::MsaaRetrofit;

/// Pixels whose samples differ: by the resolve's own test (the depth key,
/// through the CPU reference) and by the raw depth-buffer samples.
pub(crate) struct Complexity {
    pub(crate) pixels: u64,
    pub(crate) complex_key: u64,
    pub(crate) complex_depth: u64,
    /// With an opt-in test: pixels whose result differs from the exact
    /// resolve's (fast path without the option), and the largest difference
    /// of any attachment component or depth.
    pub(crate) option_changed: u64,
    pub(crate) option_max_difference: f64,
}

pub(crate) fn count_complex(
    gl: &glow::Context,
    msaa: &MsaaRetrofit,
    params: &ResolveParams,
    exact: &ResolveParams,
) -> deferred_msaa::Result<Complexity> {
    let mut readback = Readback::new(gl)?;
    let (depth_ref, color_refs, _) = msaa.inputs()?;
    let read = (|| {
        let colors = color_refs
            .iter()
            .map(|t| readback.read(gl, *t, 1))
            .collect::<deferred_msaa::Result<Vec<_>>>()?;
        let depth = readback.read(gl, depth_ref, 1)?;
        Ok::<_, deferred_msaa::Error>((colors, depth))
    })();
    readback.destroy(gl);
    let (colors, depth) = read?;
    let cpu_for = |params: &ResolveParams| CpuResolve {
        settings: params.settings,
        rules: msaa.rules().to_vec(),
        key_source: match msaa.key() {
            KeySource::Depth => CpuKeySource::Depth(params.projection),
            _ => CpuKeySource::Position(1),
        },
        clear_depth: params.projection.clear_depth,
        footprint: params.footprint(),
        normal: None,
        camera: CpuCamera::of(params),
    };
    let cpu = cpu_for(params);
    let cpu_exact = cpu_for(exact);
    let with_option = params.settings != exact.settings;
    let mut c = Complexity {
        pixels: 0,
        complex_key: 0,
        complex_depth: 0,
        option_changed: 0,
        option_max_difference: 0.0,
    };
    for y in 0..depth.height {
        for x in 0..depth.width {
            let px = pixel_samples(&depth, &colors, x, y);
            c.pixels += 1;
            let at = Some(PixelPlace {
                x,
                y,
                width: depth.width,
                height: depth.height,
            });
            let resolved = cpu.resolve_pixel_at(&px, at);
            let complex = resolved.complex;
            if with_option {
                let want = cpu_exact.resolve_pixel_at(&px, at);
                let mut worst = (resolved.depth - want.depth).abs();
                for (a, b) in resolved.attachments.iter().zip(&want.attachments) {
                    for (x, y) in a.iter().zip(b) {
                        // NaN stays NaN; only finite differences count.
                        if x.is_finite() && y.is_finite() {
                            worst = worst.max((x - y).abs());
                        }
                    }
                }
                c.option_changed += (worst > 0.0) as u64;
                c.option_max_difference = c.option_max_difference.max(worst);
            }
            c.complex_key += complex as u64;
            c.complex_depth +=
                px.depth
                    .iter()
                    .any(|d| d.to_bits() != px.depth[0].to_bits()) as u64;
        }
    }
    Ok(c)
}

pub(crate) struct Stats {
    pub(crate) median: f64,
    pub(crate) q1: f64,
    pub(crate) q3: f64,
    pub(crate) min: f64,
    pub(crate) max: f64,
}

pub(crate) fn stats(times: &[f64]) -> Stats {
    let mut s = times.to_vec();
    s.sort_by(f64::total_cmp);
    Stats {
        median: quantile(&s, 0.5),
        q1: quantile(&s, 0.25),
        q3: quantile(&s, 0.75),
        min: s.first().copied().unwrap_or(f64::NAN),
        max: s.last().copied().unwrap_or(f64::NAN),
    }
}

#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Method {
    ResolveFast,
    ResolveExact,
    ResolveNoFast,
    Blit,
    BlitColor,
    FloorExact,
    FloorPosition,
    Trivial,
}

impl Method {
    pub(crate) const ALL: [Method; 8] = [
        Method::ResolveFast,
        Method::ResolveExact,
        Method::ResolveNoFast,
        Method::Blit,
        Method::BlitColor,
        Method::FloorExact,
        Method::FloorPosition,
        Method::Trivial,
    ];
    pub(crate) fn key(self) -> &'static str {
        match self {
            Method::ResolveFast => "resolve_median_smooth_fast",
            Method::ResolveExact => "resolve_median_smooth_fast_exact",
            Method::ResolveNoFast => "resolve_median_smooth_nofast",
            Method::Blit => "blit_x3_depth",
            Method::BlitColor => "blit_x3",
            Method::FloorExact => "floor_exact_test",
            Method::FloorPosition => "floor_position_test",
            Method::Trivial => "fullscreen_trivial",
        }
    }
    pub(crate) fn label(self) -> &'static str {
        match self {
            Method::ResolveFast => {
                "resolve median smooth, fast path on (with the opt-in test if asked)"
            }
            Method::ResolveExact => "resolve median smooth, fast path on, exact test",
            Method::ResolveNoFast => "resolve median smooth, fast path off",
            Method::Blit => "3x glBlitFramebuffer + depth (hardware resolve)",
            Method::BlitColor => "3x glBlitFramebuffer, colour only",
            Method::FloorExact => "floor: the exact test's reads, sample 0 written",
            Method::FloorPosition => "floor: the position test's reads, sample 0 written",
            Method::Trivial => "trivial full-screen pass (3 outputs)",
        }
    }
}
