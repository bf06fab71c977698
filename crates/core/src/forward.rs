//! The forward target: MSAA for what a host draws forward after lighting
//! (light cubes, transparent objects, particles), which the G-buffer's
//! resolve never sees.
//!
//! [`MsaaRetrofit::begin_forward`](crate::MsaaRetrofit::begin_forward)
//! copies the host's lit image into every sample of a multisampled colour
//! texture (`forward_fill.frag`) and attaches it with the twins'
//! multisampled depth, which still holds what the geometry pass drew. The
//! host draws its forward objects into that framebuffer unchanged, tested
//! against per-sample depth, and
//! [`MsaaRetrofit::finish_forward`](crate::MsaaRetrofit::finish_forward)
//! averages each pixel's samples back into the host's lit image
//! (`forward_resolve.frag`, in the blend domain of
//! [`RetrofitOptions::layer_mix`](crate::RetrofitOptions::layer_mix)),
//! leaving pixels no forward object touched as they were.

use crate::gbuffer::MultisampleTwin;
use crate::gl::{
    Attachment, Framebuffer, FullscreenPass, GlObject, Handle, Made, SavedState, Texture2d,
    Texture2dMultisample, TextureRef, VertexArray, check_error,
};
use crate::layer_mix::{LayerMix, MixKind, mix_domain_source, set_srgb};
use crate::lit_output::{LitOutput, bind_for_reading};
use crate::{Error, Result};
use glow::HasContext;

/// The forward pass's fill: `forward_fill.frag`.
pub const FORWARD_FILL_FRAG: &str = include_str!("forward_fill.frag");

/// The forward pass's resolve: `forward_resolve.frag`.
pub const FORWARD_RESOLVE_FRAG: &str = include_str!("forward_resolve.frag");

/// The multisampled forward target of one lit output (see the module).
#[derive(Debug)]
pub(crate) struct ForwardTarget {
    output: LitOutput,
    /// The host's lit image alone (`None`: the default framebuffer).
    output_fbo: Option<Framebuffer>,
    /// The lit image as it was before the forward objects.
    lit: Texture2d,
    lit_fbo: Framebuffer,
    /// The lit image in every sample, then the forward objects.
    color: Texture2dMultisample,
    /// `color` and the twins' depth: what the host draws into.
    fbo: Framebuffer,
    fill: FullscreenPass,
    resolve: FullscreenPass,
    vao: VertexArray,
    /// The mix the resolve was compiled for.
    mix: LayerMix,
    /// `begin` ran and `finish` has not.
    pub(crate) drawing: bool,
}

impl GlObject for ForwardTarget {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.output_fbo.handles(out);
        self.lit.handles(out);
        self.lit_fbo.handles(out);
        self.color.handles(out);
        self.fbo.handles(out);
        self.fill.handles(out);
        self.resolve.handles(out);
        self.vao.handles(out);
    }
}

impl ForwardTarget {
    /// Make the forward target of `output` over `twin`'s depth, its
    /// resolve in the domain `mix` gives `output`'s format.
    pub(crate) fn new(
        gl: &glow::Context,
        output: LitOutput,
        twin: &MultisampleTwin,
        mix: &LayerMix,
    ) -> Result<Self> {
        let depth_spec = twin
            .specs
            .iter()
            .zip(&twin.textures)
            .find(|(s, _)| s.format.is_depth())
            .ok_or_else(|| Error::Retrofit {
                attachment: "GL_DEPTH_ATTACHMENT".into(),
                reason: "the forward target tests against the G-buffer's multisampled depth, and the host framebuffer has none".into(),
            })?;
        let (w, h) = (twin.width, twin.height);
        let format = output.copy_format();
        Made::build(gl, |made| {
            let output_fbo = output
                .framebuffer(gl, "forward target: host output", &[])?
                .map(|f| made.keep(f));
            let lit = made.keep(Texture2d::new(
                gl,
                "forward target: lit copy",
                format,
                w,
                h,
            )?);
            let lit_fbo = made.keep(Framebuffer::new(
                gl,
                "forward target: lit copy",
                &[(Attachment::Color(0), TextureRef::from(&lit))],
                &[Some(0)],
            )?);
            let color = made.keep(Texture2dMultisample::new(
                gl,
                "forward target colour",
                format,
                w,
                h,
                twin.samples,
            )?);
            if color.samples != twin.samples {
                return Err(Error::Unsupported {
                    feature: format!("the forward target's {} colour", format.name()),
                    requires: format!("{} samples, as the G-buffer's twins have", twin.samples),
                    found: format!("{} samples", color.samples),
                });
            }
            let fbo = made.keep(Framebuffer::new(
                gl,
                "forward target",
                &[
                    (Attachment::Color(0), TextureRef::from(&color)),
                    (depth_spec.0.point, TextureRef::from(depth_spec.1)),
                ],
                &[Some(0)],
            )?);
            let fill = made.keep(FullscreenPass::new(
                gl,
                "forward target fill",
                &crate::gl::ShaderSource::new().part("forward_fill.frag", FORWARD_FILL_FRAG),
                &[("o_color", 0)],
            )?);
            fill.program()
                .set_at_setup(gl, |p| p.set_i32(gl, "u_lit", 0));
            let kind = MixKind::of(mix, &output)?;
            let curve = match mix {
                LayerMix::Curve(source) => Some(source.as_str()),
                _ => None,
            };
            let resolve = made.keep(FullscreenPass::new(
                gl,
                &format!("forward target resolve ({})", kind.define()),
                &mix_domain_source(kind, curve)
                    .define("FORWARD_SAMPLES", &twin.samples.to_string())
                    .part("forward_resolve.frag", FORWARD_RESOLVE_FRAG),
                &[("o_color", 0)],
            )?);
            resolve.program().set_at_setup(gl, |p| {
                p.set_i32(gl, "u_forward", 0);
                p.set_i32(gl, "u_lit", 1);
                p.set_i32(gl, "u_samples", twin.samples as i32);
            });
            let vao = made.keep(VertexArray::new(gl, "forward target passes")?);
            Ok(ForwardTarget {
                output,
                output_fbo,
                lit,
                lit_fbo,
                color,
                fbo,
                fill,
                resolve,
                vao,
                mix: mix.clone(),
                drawing: false,
            })
        })
    }

    /// Whether this target serves `host`, written as `framebuffer_srgb`
    /// says, resolved with `mix`.
    pub(crate) fn serves(
        &self,
        host: Option<glow::Framebuffer>,
        framebuffer_srgb: bool,
        mix: &LayerMix,
    ) -> bool {
        self.output.same(host, framebuffer_srgb) && &self.mix == mix
    }

    /// The multisampled framebuffer the host draws into.
    pub(crate) fn framebuffer(&self) -> glow::Framebuffer {
        self.fbo.raw()
    }

    /// What of the target someone other than the crate deleted (a
    /// render-target wrapper that deletes what it wraps when dropped), in
    /// words naming it; `None` while every object exists.
    pub(crate) fn deleted(&self, gl: &glow::Context) -> Option<String> {
        unsafe {
            if !gl.is_framebuffer(self.fbo.raw()) {
                return Some(format!(
                    "the forward target's framebuffer {} (the one MsaaRetrofit::begin_forward returns)",
                    self.fbo.raw().0
                ));
            }
            if !gl.is_texture(self.color.raw()) {
                return Some(format!(
                    "the forward target's multisampled colour texture {} (attached to framebuffer {}, which begin_forward returns)",
                    self.color.raw().0,
                    self.fbo.raw().0
                ));
            }
            if !gl.is_framebuffer(self.lit_fbo.raw()) || !gl.is_texture(self.lit.raw()) {
                return Some(format!(
                    "the forward target's copy of the lit image (texture {}, framebuffer {})",
                    self.lit.raw().0,
                    self.lit_fbo.raw().0
                ));
            }
        }
        None
    }

    /// The output it serves.
    pub(crate) fn output(&self) -> Option<glow::Framebuffer> {
        self.output.host
    }

    /// The bytes it allocates.
    pub(crate) fn bytes(&self) -> u64 {
        let texels = u64::from(self.lit.width) * u64::from(self.lit.height);
        texels * u64::from(self.lit.format.bytes_per_texel()) + self.color.bytes()
    }

    /// Copy the lit image aside and into every sample of the forward
    /// target; the framebuffer the host draws its forward objects into.
    /// The caller saves the host's state.
    pub(crate) fn begin(&mut self, gl: &glow::Context) -> Result<glow::Framebuffer> {
        let (w, h) = (self.lit.width as i32, self.lit.height as i32);
        unsafe {
            // Bits as stored: the copy has the image's own encoding when
            // the host's writes were encoded, else plain unorm.
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            bind_for_reading(gl, self.output_fbo.as_ref());
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(self.lit_fbo.raw()));
            gl.blit_framebuffer(
                0,
                0,
                w,
                h,
                0,
                0,
                w,
                h,
                glow::COLOR_BUFFER_BIT,
                glow::NEAREST,
            );
            self.fill.begin(gl, &self.fbo);
            gl.disable(glow::STENCIL_TEST);
            set_srgb(gl, self.output.srgb_writes);
            TextureRef::from(&self.lit).bind(gl, 0);
        }
        self.fill.draw(gl, &self.vao);
        check_error(gl, "filling the forward target with the lit image")?;
        self.drawing = true;
        Ok(self.fbo.raw())
    }

    /// Average each touched pixel's samples into the host's lit image.
    /// The caller saves the host's state.
    pub(crate) fn finish(&mut self, gl: &glow::Context) -> Result<()> {
        self.drawing = false;
        unsafe {
            match &self.output_fbo {
                Some(target) => {
                    self.resolve.begin(gl, target);
                }
                None => {
                    gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                    SavedState::prepare_fullscreen_pass(gl);
                    gl.disable(glow::DEPTH_TEST);
                    gl.viewport(0, 0, self.lit.width as i32, self.lit.height as i32);
                    self.resolve.program().bind(gl);
                }
            }
            gl.disable(glow::STENCIL_TEST);
            set_srgb(gl, self.output.srgb_writes);
            TextureRef::from(&self.color).bind(gl, 0);
            TextureRef::from(&self.lit).bind(gl, 1);
        }
        self.resolve.draw(gl, &self.vao);
        check_error(gl, "resolving the forward target into the lit image")
    }
}
