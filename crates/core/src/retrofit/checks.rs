//! What the retrofit refuses, and how its public calls keep GL errors
//! apart from the host's: an attachment it does not resolve, a host with
//! no point left for the stencil copy, an output that is no complete
//! framebuffer, errors the host left pending.

use crate::gl::output_points;
use crate::gl::{Attachment, check_error};
use crate::host::HostFramebuffer;
use crate::{Error, Result};

/// Why an attachment an option names is not one the retrofit resolves:
/// attached but in none of the draw buffers, or nothing attached at all.
pub(super) fn not_resolved(host: &HostFramebuffer, point: Attachment, what: &str) -> String {
    if host.undrawn.contains(&point) {
        format!(
            "{what}, but it is in none of the host framebuffer's draw buffers (glDrawBuffers): the geometry pass cannot write it, so the retrofit neither twins nor resolves it; add it to the draw buffers, or give the option no attachment there"
        )
    } else {
        format!("{what}, but nothing is attached there")
    }
}

/// The resolve writes a depth-stencil host's reference-sample index as one
/// more colour output after the host's drawn colours: a host that uses
/// every point leaves none for it, which must be refused here, in one line,
/// rather than fail later as a GL error on a point the context lacks.
pub(super) fn check_stencil_copy_point(gl: &glow::Context, host: &HostFramebuffer) -> Result<()> {
    let points = output_points(gl);
    let needed = host.colors.len() as u32 + 1;
    if needed <= points {
        return Ok(());
    }
    Err(Error::Retrofit {
        attachment: host.depth.point.name(),
        reason: format!(
            "the stencil copy's reference sample needs a colour output after the {} drawn colour \
             attachments, and this context has {points} (GL_MAX_COLOR_ATTACHMENTS, \
             GL_MAX_DRAW_BUFFERS); copy the stencil by blit (StencilCopy::Blit, DMSAA_STENCIL_BLIT: the sample the driver picks, no index needed), draw one colour attachment fewer, or attach {} without its stencil",
            host.colors.len(),
            host.depth.requested_format
        ),
    })
}

/// Before a public call's GL calls: an error the host left pending is not
/// the call's; it is logged and cleared, so that [`settle`] sees the call's
/// own.
pub(super) fn clear_host_errors(gl: &glow::Context) {
    if let Err(e) = check_error(gl, "the host's GL calls before this call") {
        log::warn!("{e}");
    }
}

/// The end of a public call, after the host's state is back: any GL error
/// the call's own GL calls left pending is drained, so that none is left for
/// the host whatever the result; after a call that succeeded it is the
/// call's error (one no step of the call checked, which the misuse fuzzer
/// has not met).
pub(super) fn settle<T>(gl: &glow::Context, stage: &str, result: Result<T>) -> Result<T> {
    let pending = check_error(gl, stage);
    let value = result?;
    pending.map(|()| value)
}

/// The second layer's lighting output, checked when `begin_second_layer`
/// is given it (`finish_second_layer` takes begin's alone): a name
/// that is no framebuffer, or a framebuffer GL calls incomplete (the
/// default framebuffer of a surfaceless context, say), is refused saying
/// so, rather than as the GL error a copy from it raises. The read binding
/// is put back.
pub(super) fn check_output(gl: &glow::Context, output: Option<glow::Framebuffer>) -> Result<()> {
    use glow::HasContext;
    let name = || {
        output.map_or("the default framebuffer (0)".to_string(), |f| {
            format!("framebuffer {}", f.0)
        })
    };
    if let Some(f) = output {
        if !unsafe { gl.is_framebuffer(f) } {
            return Err(Error::invalid(format!(
                "the lighting output, {}, is not a framebuffer object (glIsFramebuffer is false)",
                name()
            )));
        }
    }
    let status = unsafe {
        let read = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING);
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, output);
        let status = gl.check_framebuffer_status(glow::READ_FRAMEBUFFER);
        gl.bind_framebuffer(
            glow::READ_FRAMEBUFFER,
            std::num::NonZeroU32::new(read as u32)
                .map(glow::NativeFramebuffer)
                .filter(|&f| gl.is_framebuffer(f)),
        );
        status
    };
    if status != glow::FRAMEBUFFER_COMPLETE {
        return Err(Error::invalid(format!(
            "the lighting output, {}, is incomplete ({}): the second layer reads the lit image \
             from it",
            name(),
            crate::gl::framebuffer_status_name(status)
        )));
    }
    Ok(())
}

/// Which of the draw and read framebuffer bindings the host left on `ours`
/// (a framebuffer of the crate's it drew into in place of its output).
pub(super) fn bound_to(gl: &glow::Context, ours: glow::Framebuffer) -> (bool, bool) {
    use glow::HasContext;
    let get = |pname| unsafe { gl.get_parameter_i32(pname) } as u32;
    (
        get(glow::DRAW_FRAMEBUFFER_BINDING) == ours.0.get(),
        get(glow::READ_FRAMEBUFFER_BINDING) == ours.0.get(),
    )
}

/// After a finish, with the host's state back: where the host had bound
/// the crate's framebuffer (`bound`, from [`bound_to`]), bind `output`
/// instead, as if the host had drawn into its output; so a read-back
/// (`glReadBuffer(GL_BACK)`, `glReadPixels`) or a post pass that follows
/// reads the output, never the crate's multisampled target.
pub(super) fn bind_output_where(
    gl: &glow::Context,
    bound: (bool, bool),
    output: Option<glow::Framebuffer>,
) {
    use glow::HasContext;
    unsafe {
        match bound {
            (true, true) => gl.bind_framebuffer(glow::FRAMEBUFFER, output),
            (true, false) => gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, output),
            (false, true) => gl.bind_framebuffer(glow::READ_FRAMEBUFFER, output),
            (false, false) => {}
        }
    }
}

/// An object of the crate's that the host's code deleted (`what` names it):
/// the error naming it and the fix.
pub(super) fn deleted_by_host(target: &str, what: String) -> Error {
    Error::Retrofit {
        attachment: target.into(),
        reason: format!(
            "{what} was deleted by someone other than the retrofit, which owns it (a render-target wrapper that deletes what it wraps when dropped?); wrap it without taking ownership, and call refresh (dmsaa_refresh) to make it anew"
        ),
    }
}
