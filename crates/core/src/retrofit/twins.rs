//! The multisampled twins' formats, and clearing them to the host's clear
//! values.

use super::options::TwinClear;
use crate::gbuffer::MultisampleTwin;
use crate::gl::{Attachment, Format, Framebuffer, TextureRef, check_error};
use crate::host::{HostAttachment, HostFramebuffer};
use crate::{Error, Result};
use glow::HasContext;

/// Whether `format` stores unsigned normalised components (`GL_RGBA8`,
/// `GL_RGB10_A2`, ...): no negative value, so a normal in it is packed.
pub(super) fn unsigned_normalised(format: Format) -> bool {
    matches!(
        format.properties().component,
        crate::gl::format::ComponentType::Unorm
    )
}

/// The format of a colour attachment's multisampled twin: the host's own
/// where the driver multisamples it, else its stand-in
/// ([`Format::multisample_stand_in`]).
pub(super) fn twin_format(gl: &glow::Context, a: &HostAttachment, samples: u32) -> Result<Format> {
    if multisamples(gl, a.format, samples)? {
        return Ok(a.format);
    }
    let wider = a.format.multisample_stand_in();
    if let Some(wider) = wider {
        if multisamples(gl, wider, samples)? {
            log::info!(
                "{}: {} cannot be multisampled here; its twin is {wider}",
                a.point.name(),
                a.requested_format
            );
            return Ok(wider);
        }
    }
    Err(Error::UnsupportedFormat {
        attachment: a.point.name(),
        format: a.requested_format.clone(),
        reason: format!(
            "the driver cannot render to a multisampled texture of it{}",
            wider
                .map(|w| format!(" nor of its stand-in GL_{w}"))
                .unwrap_or_default()
        ),
    })
}

/// Whether a `samples`x multisample texture of `format` can be made and
/// rendered to: a 1x1 probe, freed at once. A count the format supports
/// at others is the count's error, not the format's.
fn multisamples(gl: &glow::Context, format: Format, samples: u32) -> Result<bool> {
    let _ = check_error(gl, "before probing a multisample format");
    let texture =
        match crate::gl::Texture2dMultisample::new(gl, "format probe", format, 1, 1, samples) {
            Ok(t) => t,
            Err(e @ Error::UnsupportedSampleCount { .. }) => {
                let _ = check_error(gl, "probing a multisample format");
                return match &e {
                    Error::UnsupportedSampleCount { supported, .. } if !supported.is_empty() => {
                        Err(e)
                    }
                    _ => Ok(false),
                };
            }
            Err(Error::Gl { .. }) => return Ok(false),
            Err(e) => return Err(e),
        };
    let point = if format.is_depth() {
        Attachment::for_depth_format(format)
    } else {
        Attachment::Color(0)
    };
    let draw: &[Option<u32>] = if format.is_depth() { &[] } else { &[Some(0)] };
    let fbo = Framebuffer::new(
        gl,
        "format probe",
        &[(point, TextureRef::from(&texture))],
        draw,
    );
    let complete = fbo.is_ok();
    if let Ok(f) = fbo {
        f.destroy(gl);
    }
    texture.destroy(gl);
    let _ = check_error(gl, "probing a multisample format");
    Ok(complete)
}

/// Clear `twin`'s images to `clear`'s values: each colour attachment of
/// `host` at the draw buffer the host maps to it, by its sample kind, then
/// depth and stencil. The caller keeps the host's state.
pub(super) fn clear_twins(
    gl: &glow::Context,
    host: &HostFramebuffer,
    twin: &MultisampleTwin,
    clear: &TwinClear,
) {
    use crate::gl::format::SampleKind;
    unsafe {
        twin.fbo.bind(gl);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::RASTERIZER_DISCARD);
        gl.color_mask(true, true, true, true);
        gl.depth_mask(true);
        gl.stencil_mask(0xFF);
        for a in &host.colors {
            let Attachment::Color(n) = a.point else {
                continue;
            };
            let Some(buffer) = host.draw_buffers.iter().position(|b| *b == Some(n)) else {
                continue;
            };
            let value = clear
                .colors
                .iter()
                .find(|(c, _)| Attachment::from(*c) == a.point)
                .map_or([0.0; 4], |(_, v)| *v);
            let buffer = buffer as u32;
            match a.format.sample_kind() {
                SampleKind::Float => gl.clear_buffer_f32_slice(glow::COLOR, buffer, &value),
                SampleKind::Uint => gl.clear_buffer_u32_slice(
                    glow::COLOR,
                    buffer,
                    &value.map(|v| v.max(0.0) as u32),
                ),
                SampleKind::Int => {
                    gl.clear_buffer_i32_slice(glow::COLOR, buffer, &value.map(|v| v as i32))
                }
            }
        }
        if host.depth.format.has_stencil() {
            gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, clear.depth, clear.stencil);
        } else {
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[clear.depth]);
        }
    }
}

/// Clear `twin`'s depth alone to `depth` (its stencil, colours and the
/// host's state as they are; the caller keeps the host's state).
pub(super) fn clear_twin_depth(gl: &glow::Context, twin: &MultisampleTwin, depth: f32) {
    unsafe {
        twin.fbo.bind(gl);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::RASTERIZER_DISCARD);
        gl.depth_mask(true);
        gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[depth]);
    }
}
