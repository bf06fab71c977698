//! Which sample counts a multisample texture of a format really gets: the
//! candidates the context offers, each probed, since drivers round
//! requests. A leaf below the textures (whose errors list the counts) and
//! the capabilities.

use super::{Format, check_error};
use glow::HasContext;

/// The distinct sample counts a `GL_TEXTURE_2D_MULTISAMPLE` of `format`
/// really gets, ascending. Candidates come from `glGetInternalformativ`
/// where the context has it, else the powers of two up to the format's
/// `GL_MAX_*_SAMPLES`; each is then allocated at 1x1 and read back, because
/// drivers round requests.
pub(super) fn sample_counts_for(gl: &glow::Context, format: Format) -> Vec<u32> {
    let v = gl.version();
    let iq = (v.major, v.minor) >= (4, 2)
        || gl
            .supported_extensions()
            .contains("GL_ARB_internalformat_query");
    let mut candidates: Vec<u32> = Vec::new();
    if iq {
        let mut n = [0i32];
        unsafe {
            gl.get_internal_format_i32_slice(
                glow::TEXTURE_2D_MULTISAMPLE,
                format.internal_format(),
                glow::NUM_SAMPLE_COUNTS,
                &mut n,
            )
        };
        if n[0] > 0 && n[0] < 64 {
            let mut counts = vec![0i32; n[0] as usize];
            unsafe {
                gl.get_internal_format_i32_slice(
                    glow::TEXTURE_2D_MULTISAMPLE,
                    format.internal_format(),
                    glow::SAMPLES,
                    &mut counts,
                )
            };
            candidates.extend(counts.into_iter().filter(|&c| c > 0).map(|c| c as u32));
        }
    }
    if candidates.is_empty() {
        let max = if format.is_depth() {
            get_u32(gl, glow::MAX_DEPTH_TEXTURE_SAMPLES)
        } else if format.sample_kind() != super::format::SampleKind::Float {
            get_u32(gl, glow::MAX_INTEGER_SAMPLES)
        } else {
            get_u32(gl, glow::MAX_COLOR_TEXTURE_SAMPLES)
        };
        let mut c = 2;
        while c <= max.min(64) {
            candidates.push(c);
            c *= 2;
        }
    }
    let _ = check_error(gl, "querying sample counts");
    let mut real: Vec<u32> = Vec::new();
    for requested in candidates {
        if let Some(n) = probe_samples(gl, format, requested) {
            if !real.contains(&n) {
                real.push(n);
            }
        }
    }
    real.sort_unstable();
    real
}

fn probe_samples(gl: &glow::Context, format: Format, requested: u32) -> Option<u32> {
    unsafe {
        let raw = gl.create_texture().ok()?;
        gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(raw));
        gl.tex_image_2d_multisample(
            glow::TEXTURE_2D_MULTISAMPLE,
            requested as i32,
            format.internal_format() as i32,
            1,
            1,
            true,
        );
        let ok = check_error(gl, "probing a sample count").is_ok();
        let n =
            gl.get_tex_level_parameter_i32(glow::TEXTURE_2D_MULTISAMPLE, 0, glow::TEXTURE_SAMPLES);
        gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
        gl.delete_texture(raw);
        (ok && n > 0).then_some(n as u32)
    }
}

/// A `glGetIntegerv` value, negative ones as 0.
pub(super) fn get_u32(gl: &glow::Context, pname: u32) -> u32 {
    unsafe { gl.get_parameter_i32(pname) }.max(0) as u32
}
