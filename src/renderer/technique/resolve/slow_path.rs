//! Which pixels the resolve took its slow path on: the last frame's resolve
//! run again with its complex-pixel output (`COMPLEX_OUTPUT` in
//! `resolve.frag`) drawn into a scratch R8 mask, the resolved attachments
//! discarded (their draw buffers are `GL_NONE`), so the G-buffer is left as
//! the frame made it.

use crate::frame::Frame as ResolveFrame;
use crate::gl::{Attachment, Format, Framebuffer, Made, Texture2d, TextureRef};
use crate::retrofit::MsaaRetrofit;
use crate::{Error, Result};
use glow::HasContext;

/// The slow-path mask of `retrofit`'s current twins under `params`, row 0
/// at the top: 255 where the resolve blended samples, 0 where the
/// uniform-pixel fast path copied sample 0 (every pixel is slow with the
/// fast path off).
pub(crate) fn slow_path_mask(
    gl: &glow::Context,
    retrofit: &mut MsaaRetrofit,
    frame: &ResolveFrame,
) -> Result<image::GrayImage> {
    let (w, h) = retrofit.host().size();
    let colors = retrofit.host().colors.len();
    // Draw buffer k (resolved attachment k) goes nowhere; the mask output,
    // draw buffer `colors`, into the mask.
    let mut draw: Vec<Option<u32>> = vec![None; colors];
    draw.push(Some(0));
    let (mask, fbo) = Made::build(gl, |made| {
        let mask = made.keep(Texture2d::new(gl, "slow-path mask", Format::R8, w, h)?);
        let fbo = made.keep(Framebuffer::new(
            gl,
            "slow-path mask",
            &[(Attachment::Color(0), TextureRef::from(&mask))],
            &draw,
        )?);
        Ok::<_, Error>((mask, fbo))
    })?;
    let result = (|| {
        // Pixels a resolve variant never draws count as fast.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo.raw()));
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
        retrofit.resolve_into(gl, &fbo, frame, true)?;
        read_r8(gl, &fbo)
    })();
    fbo.destroy(gl);
    mask.destroy(gl);
    result
}

/// Read colour attachment 0 of `fbo` (R8) as a grey image, row 0 at the top.
fn read_r8(gl: &glow::Context, fbo: &Framebuffer) -> Result<image::GrayImage> {
    let (w, h) = (fbo.width, fbo.height);
    let data = fbo.read_u8(gl, glow::RED, 1, "the slow-path mask")?;
    let mask = data
        .iter()
        .map(|&v| if v >= 128 { 255 } else { 0 })
        .collect();
    image::GrayImage::from_raw(w, h, mask)
        .ok_or_else(|| Error::invalid(format!("the slow-path mask does not hold {w}x{h} pixels")))
}
