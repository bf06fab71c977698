//! The check: every resolved pixel of every offered count against the
//! CPU reference, within each format's tolerance.

use crate::setup::*;
use deferred_msaa::gbuffer::GBufferLayout;
use deferred_msaa::gl::{Format, TextureRef};
use deferred_msaa::readback::{Readback, SampleImage, pixel_samples};
use deferred_msaa::resolve::cpu::{CpuCamera, CpuKeySource, CpuResolve, PixelPlace};
use deferred_msaa::resolve::{KeySource, ResolveSlot};
use deferred_msaa::{Error, MsaaRetrofit};
use deferred_msaa_testkit::Host;

/// The comparison of one resolve with the CPU reference.
pub(crate) struct Comparison {
    pub(crate) fast_path: bool,
    pub(crate) pixels: usize,
    pub(crate) complex: usize,
    pub(crate) ambiguous: usize,
    pub(crate) values: usize,
    pub(crate) mismatches: usize,
    pub(crate) max_abs_error: f64,
    pub(crate) max_over_tolerance: f64,
    pub(crate) worst: String,
    pub(crate) first_mismatches: Vec<String>,
    /// Why the comparison fails, when it does.
    pub(crate) failure: Option<String>,
}

pub(crate) enum Offer {
    /// The driver refused the count or gave another one.
    NotOffered(String),
    Checked {
        samples: u32,
        gl_samples: u32,
        comparisons: Vec<Comparison>,
    },
    Failed(String),
}

pub(crate) struct CheckEntry {
    pub(crate) requested: u32,
    pub(crate) layout: &'static str,
    pub(crate) offer: Offer,
}

impl CheckEntry {
    pub(crate) fn passed(&self) -> bool {
        match &self.offer {
            Offer::NotOffered(_) => true,
            Offer::Failed(_) => false,
            Offer::Checked { comparisons, .. } => comparisons.iter().all(|c| c.failure.is_none()),
        }
    }
}

/// The storage tolerance of a resolved value of `format` (see the module docs).
pub(crate) fn tolerance(format: Format, cpu: f64) -> f64 {
    match format {
        Format::R16f | Format::Rg16f | Format::Rgb16f | Format::Rgba16f | Format::R11fG11fB10f => {
            1e-5 + 1.2e-3 * cpu.abs()
        }
        Format::R32f | Format::Rg32f | Format::Rgb32f | Format::Rgba32f => 1e-4 * (1.0 + cpu.abs()),
        _ => 1.0 / 255.0,
    }
}

/// The error of `gpu` against `cpu`, and whether it is within `tol`
/// (non-finite references must be matched exactly).
pub(crate) fn judge(gpu: f32, cpu: f64, tol: f64) -> (bool, f64) {
    let g = gpu as f64;
    if cpu.is_nan() {
        return if g.is_nan() {
            (true, 0.0)
        } else {
            (false, f64::INFINITY)
        };
    }
    if cpu.is_infinite() {
        return if g == cpu {
            (true, 0.0)
        } else {
            (false, f64::INFINITY)
        };
    }
    let err = (g - cpu).abs();
    if err.is_nan() {
        return (false, f64::INFINITY);
    }
    (err <= tol, err)
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn compare(
    cpu: &CpuResolve,
    names: &[String],
    formats: &[Format],
    samples: &[SampleImage],
    depth: &SampleImage,
    resolved: &[SampleImage],
    resolved_depth: &SampleImage,
) -> Comparison {
    let mut c = Comparison {
        fast_path: cpu.settings.fast_path,
        pixels: 0,
        complex: 0,
        ambiguous: 0,
        values: 0,
        mismatches: 0,
        max_abs_error: 0.0,
        max_over_tolerance: 0.0,
        worst: String::new(),
        first_mismatches: Vec::new(),
        failure: None,
    };
    // `what` names the value; it is formatted only for the reports.
    let note = |c: &mut Comparison, what: &dyn Fn() -> String, got: f32, want: f64, tol: f64| {
        let (ok, err) = judge(got, want, tol);
        c.values += 1;
        c.max_abs_error = c.max_abs_error.max(err);
        let ratio = err / tol;
        if ratio > c.max_over_tolerance || c.worst.is_empty() {
            c.max_over_tolerance = c.max_over_tolerance.max(ratio);
            c.worst = format!("{}: gpu {got} cpu {want}", what());
        }
        if !ok {
            c.mismatches += 1;
            if c.first_mismatches.len() < 6 {
                c.first_mismatches.push(format!(
                    "{}: gpu {got} cpu {want} (tolerance {tol:.3e})",
                    what()
                ));
            }
        }
    };
    for y in 0..depth.height {
        for x in 0..depth.width {
            let px = pixel_samples(depth, samples, x, y);
            let at = PixelPlace {
                x,
                y,
                width: depth.width,
                height: depth.height,
            };
            let want = cpu.resolve_pixel_at(&px, Some(at));
            c.pixels += 1;
            c.complex += usize::from(want.complex);
            // Within rounding of a window edge or a depth tie: either answer is right.
            if want.ambiguous {
                c.ambiguous += 1;
                continue;
            }
            for (k, image) in resolved.iter().enumerate() {
                let got = image.get(0, x, y);
                for (ch, (&g, &w)) in got.iter().zip(&want.attachments[k]).enumerate() {
                    let what = || format!("({x},{y}) {}[{ch}]", names[k]);
                    note(&mut c, &what, g, w, tolerance(formats[k], w));
                }
            }
            let d = resolved_depth.get(0, x, y)[0];
            note(&mut c, &|| format!("({x},{y}) depth"), d, want.depth, 1e-6);
        }
    }
    c.failure = if c.mismatches > 0 {
        Some(format!(
            "{} of {} values outside tolerance",
            c.mismatches, c.values
        ))
    } else if c.ambiguous * 10 >= c.pixels {
        Some(format!(
            "{} of {} pixels ambiguous (at most 10 % may be)",
            c.ambiguous, c.pixels
        ))
    } else if c.complex < MIN_COMPLEX_PIXELS {
        Some(format!(
            "only {} complex pixels: the scene did not exercise the slow path",
            c.complex
        ))
    } else {
        None
    };
    c
}

/// Check one requested count for one layout; `checked` holds the real counts
/// this layout has already been checked at.
pub(crate) fn check_count(
    gl: &glow::Context,
    readback: &mut Readback,
    layout: &GBufferLayout,
    requested: u32,
    model: &Model,
    checked: &mut Vec<u32>,
) -> Result<Offer, Error> {
    let host = host_for(gl, layout, model)?;
    let result = match MsaaRetrofit::new(gl, host.fbo.raw(), &options_for(layout, requested, true))
    {
        Ok(mut msaa) => {
            let r = check_retrofit(
                gl, readback, layout, &host, &mut msaa, model, requested, checked,
            );
            msaa.destroy(gl);
            r
        }
        Err(Error::UnsupportedSampleCount { supported, .. }) => Ok(Offer::NotOffered(format!(
            "refused; the driver offers {}",
            counts_text(&supported)
        ))),
        Err(e) => Err(e),
    };
    host.destroy(gl);
    result
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn check_retrofit(
    gl: &glow::Context,
    readback: &mut Readback,
    layout: &GBufferLayout,
    host: &Host,
    msaa: &mut MsaaRetrofit,
    model: &Model,
    requested: u32,
    checked: &mut Vec<u32>,
) -> Result<Offer, Error> {
    let samples = msaa.samples();
    let gl_samples = framebuffer_samples(gl, msaa.framebuffer());
    if gl_samples != samples {
        return Ok(Offer::Failed(format!(
            "the twins' textures have {samples} samples but the framebuffer's GL_SAMPLES is {gl_samples}"
        )));
    }
    // A rounded count is checked where it is asked for itself.
    if samples != requested && (COUNTS.contains(&samples) || checked.contains(&samples)) {
        return Ok(Offer::NotOffered(format!("the driver gave {samples}x")));
    }
    checked.push(samples);
    draw_into(gl, host, msaa.begin_frame(gl)?, model)?;
    let (depth_ref, color_refs, _) = msaa.inputs()?;
    let inputs = color_refs
        .iter()
        .map(|t| readback.read(gl, *t, 1))
        .collect::<Result<Vec<_>, Error>>()?;
    let depth = readback.read(gl, depth_ref, 1)?;
    let frame = model.frame();
    let (projection, fov_y) = frame.depth_terms()?;
    let key_source = match msaa.key() {
        KeySource::Position(ResolveSlot(k)) => CpuKeySource::Position(k),
        KeySource::Depth => CpuKeySource::Depth(projection),
        KeySource::WorldPosition(_) => {
            return Err(Error::invalid("a world-space key is not measured here"));
        }
    };
    let formats: Vec<Format> = msaa.host().colors.iter().map(|a| a.format).collect();
    let names: Vec<String> = layout.colors.iter().map(|a| a.name.clone()).collect();
    let mut comparisons = Vec::new();
    for fast_path in [true, false] {
        msaa.set_options(gl, &options_for(layout, requested, fast_path))?;
        // The same frame drawn again, as the resolve requires a begun one.
        draw_into(gl, host, msaa.begin_frame(gl)?, model)?;
        msaa.resolve(gl, &frame)?;
        let resolved = host
            .colors
            .iter()
            .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1))
            .collect::<Result<Vec<_>, Error>>()?;
        let resolved_depth = readback.read(gl, TextureRef::from(&host.depth), 1)?;
        let cpu = CpuResolve {
            settings: msaa.options().resolve,
            rules: msaa.rules().to_vec(),
            key_source,
            clear_depth: projection.clear_depth,
            footprint: (fov_y / model.height as f64).tan(),
            normal: None,
            camera: CpuCamera { projection, fov_y },
        };
        comparisons.push(compare(
            &cpu,
            &names,
            &formats,
            &inputs,
            &depth,
            &resolved,
            &resolved_depth,
        ));
    }
    Ok(Offer::Checked {
        samples,
        gl_samples,
        comparisons,
    })
}

pub(crate) fn counts_text(counts: &[u32]) -> String {
    if counts.is_empty() {
        return "none".into();
    }
    counts
        .iter()
        .map(|n| format!("{n}x"))
        .collect::<Vec<_>>()
        .join(", ")
}
