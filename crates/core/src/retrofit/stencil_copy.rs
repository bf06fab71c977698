//! What copies a depth-stencil host's stencil back after the resolve.

use crate::Result;
use crate::gl::{Attachment, Format, Framebuffer, GlObject, Handle, HostImage, Made, Texture2d};
use crate::host::HostFramebuffer;
use crate::resolve::{StencilCopy, StencilPass};

/// What copies a depth-stencil host's stencil back: the resolve's reference
/// index per pixel, a framebuffer of the host's depth-stencil image alone
/// (the pass reads the index, so it must not be attached where it writes),
/// and the pass.
#[derive(Debug)]
pub(super) struct StencilCopyTargets {
    /// The resolve's reference-sample index, for a copy that reads it
    /// (`None` for [`StencilCopy::Blit`], which needs none).
    pub(super) reference: Option<Texture2d>,
    pub(super) target: Framebuffer,
    pub(super) pass: StencilPass,
}

impl GlObject for StencilCopyTargets {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.reference.handles(out);
        self.target.handles(out);
        self.pass.handles(out);
    }
}

impl StencilCopyTargets {
    pub(super) fn new(
        gl: &glow::Context,
        host: &HostFramebuffer,
        method: StencilCopy,
    ) -> Result<Self> {
        let method = method.on(gl)?;
        let (w, h) = host.size();
        Made::build(gl, |made| {
            let reference = if method == StencilCopy::Blit {
                None
            } else {
                Some(made.keep(Texture2d::new(
                    gl,
                    "resolve reference sample",
                    Format::R8ui,
                    w,
                    h,
                )?))
            };
            let depth = &host.depth;
            let images: Vec<(Attachment, HostImage)> = depth
                .host_image()
                .map(|i| (depth.point, i))
                .into_iter()
                .collect();
            let target = made.keep(Framebuffer::with_host_images(
                gl,
                "stencil copy target (host depth-stencil)",
                &[(depth.point, depth.texture_ref())],
                &images,
                &[],
            )?);
            let pass = StencilPass::new(gl, method)?;
            Ok(StencilCopyTargets {
                reference,
                target,
                pass,
            })
        })
    }
}
