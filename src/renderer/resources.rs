//! What the renderer allocates: the programs built once ([`Passes`]) and
//! the size- and layout-dependent targets ([`Frame`]), and how a resize
//! re-attaches the G-buffer's textures.

use super::options::RenderOptions;
use super::pass::background::BackgroundPass;
use super::pass::background_copy::BackgroundCopyPass;
use super::pass::geometry::GeometryPass;
use super::pass::lighting::LightingPass;
use super::pass::slots::GBufferSlots;
use super::pass::tonemap::TonemapPass;
use super::pass::transparent::TransparentPass;
use super::targets::{ColorTarget, Targets};
use super::technique::fxaa::FxaaPass;
use super::technique::smaa::SmaaPasses;
use super::technique::smaa::targets::SmaaTargets;
use crate::Result;
use crate::gbuffer::GBuffer;
use crate::gl::{
    Attachment, Framebuffer, GlObject, GpuTimer, Handle, Made, Texture2d, TextureRef, VertexArray,
    check_error, destroy_object, framebuffer_status_name,
};
use crate::resolve::SelectionFlag;
use crate::retrofit::MsaaRetrofit;
use glow::HasContext;

/// Programs, the full-screen vertex array and the timer: built once.
#[derive(Debug)]
pub(super) struct Passes {
    pub(super) background: BackgroundPass,
    pub(super) background_copy: BackgroundCopyPass,
    pub(super) geometry: GeometryPass,
    pub(super) lighting: LightingPass,
    pub(super) transparent: TransparentPass,
    pub(super) tonemap: TonemapPass,
    pub(super) fxaa: FxaaPass,
    /// SMAA's programs and tables, built when SMAA is first asked for.
    pub(super) smaa: Option<SmaaPasses>,
    pub(super) fullscreen: VertexArray,
    pub(super) timer: GpuTimer,
}

impl GlObject for Passes {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.background.handles(out);
        self.background_copy.handles(out);
        self.geometry.handles(out);
        self.lighting.handles(out);
        self.transparent.handles(out);
        self.tonemap.handles(out);
        self.fxaa.handles(out);
        self.smaa.handles(out);
        self.fullscreen.handles(out);
        self.timer.handles(out);
    }
}

impl Passes {
    pub(super) fn new(gl: &glow::Context, slots: GBufferSlots, smaa: bool) -> Result<Self> {
        Made::build(gl, |made| {
            Ok(Passes {
                background: made.keep(BackgroundPass::new(gl)?),
                background_copy: made.keep(BackgroundCopyPass::new(gl)?),
                geometry: made.keep(GeometryPass::new(gl, slots)?),
                lighting: made.keep(LightingPass::new(gl, slots)?),
                transparent: made.keep(TransparentPass::new(gl)?),
                tonemap: made.keep(TonemapPass::new(gl)?),
                fxaa: made.keep(FxaaPass::new(gl)?),
                smaa: if smaa {
                    Some(made.keep(SmaaPasses::new(gl)?))
                } else {
                    None
                },
                fullscreen: made.keep(VertexArray::new(gl, "renderer full-screen triangle")?),
                timer: made.keep(GpuTimer::new(gl, false)?),
            })
        })
    }

    pub(super) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

/// The size- and layout-dependent resources: the host G-buffer, the
/// retrofit on it, and the other targets (SMAA's beside the rest).
#[derive(Debug)]
pub(super) struct Frame {
    pub(super) gbuffer: GBuffer,
    pub(super) retrofit: Option<MsaaRetrofit>,
    pub(super) targets: Targets,
    /// SMAA's edges, weights and output, when SMAA is on.
    pub(super) smaa: Option<SmaaTargets>,
}

impl GlObject for Frame {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.gbuffer.handles(out);
        self.retrofit.handles(out);
        self.targets.handles(out);
        self.smaa.handles(out);
    }
}

impl Frame {
    pub(super) fn new(
        gl: &glow::Context,
        options: &RenderOptions,
        opt_out_flag: Option<SelectionFlag>,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let gbuffer = made.keep(GBuffer::new(
                gl,
                &options.layout,
                options.width,
                options.height,
            )?);
            let retrofit = if options.aa.is_multisampled() {
                Some(made.keep(MsaaRetrofit::new(
                    gl,
                    gbuffer.fbo.raw(),
                    &options.retrofit_options(opt_out_flag),
                )?))
            } else {
                None
            };
            let targets = made.keep(Targets::new(gl, &gbuffer.depth, options.fxaa)?);
            let smaa = if options.smaa.is_some() {
                Some(made.keep(SmaaTargets::new(gl, options.width, options.height)?))
            } else {
                None
            };
            Ok(Frame {
                gbuffer,
                retrofit,
                targets,
                smaa,
            })
        })
    }

    /// The last target of the frame: SMAA's or FXAA's output, or the
    /// tonemapped image.
    pub(super) fn final_target(&self) -> &ColorTarget {
        match (&self.smaa, &self.targets.fxaa) {
            (Some(smaa), _) => &smaa.out,
            (None, Some(fxaa)) => fxaa,
            (None, None) => &self.targets.ldr,
        }
    }

    pub(super) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

/// Free a G-buffer's textures that no framebuffer holds any more.
pub(super) fn free_textures(gl: &glow::Context, colors: Vec<Texture2d>, depth: Option<Texture2d>) {
    for t in colors {
        t.destroy(gl);
    }
    if let Some(t) = depth {
        t.destroy(gl);
    }
}

/// Attach `colors` (colour `k` at `GL_COLOR_ATTACHMENTk`) and `depth` to the
/// existing framebuffer `fbo`, as an engine does when it re-allocates its
/// G-buffer on resize, and check completeness.
pub(super) fn attach_gbuffer_textures(
    gl: &glow::Context,
    fbo: &mut Framebuffer,
    colors: &[Texture2d],
    depth: &Texture2d,
) -> Result<()> {
    let mut attachments: Vec<(Attachment, TextureRef)> = colors
        .iter()
        .enumerate()
        .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
        .collect();
    attachments.push((
        Attachment::for_depth_format(depth.format),
        TextureRef::from(depth),
    ));
    let status = unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo.raw()));
        for (point, texture) in &attachments {
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                point.gl_enum(),
                glow::TEXTURE_2D,
                Some(texture.raw()),
                0,
            );
        }
        let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        status
    };
    check_error(
        gl,
        &format!("re-attaching the textures of framebuffer `{}`", fbo.label),
    )?;
    if status != glow::FRAMEBUFFER_COMPLETE {
        return Err(deferred_msaa::Error::FramebufferIncomplete {
            label: fbo.label.clone(),
            status: framebuffer_status_name(status),
        }
        .into());
    }
    fbo.width = depth.width;
    fbo.height = depth.height;
    fbo.attachments = attachments;
    Ok(())
}
