//! The second resolved layer ([`ResolveSettings::layers`](crate::resolve::ResolveSettings::layers)
//! = 2): the crate's own single-sample G-buffer that the second cluster of
//! each pixel is resolved into, its coverage, and the passes around the
//! host's second lighting — copies of the host's G-buffer in and out, and
//! the mix of the two lit layers (`second_layer.frag`).
//!
//! The host's lighting runs twice, unchanged:
//! [`MsaaRetrofit::begin_second_layer`](crate::MsaaRetrofit::begin_second_layer)
//! keeps the lit first layer and puts the second layer into the host's
//! textures, and [`MsaaRetrofit::finish_second_layer`](crate::MsaaRetrofit::finish_second_layer)
//! mixes the two by coverage and puts the first layer back.

use crate::gl::{
    Attachment, Format, Framebuffer, FullscreenPass, GlObject, Handle, Made, Texture2d, TextureRef,
    VertexArray, check_error,
};
use crate::host::HostFramebuffer;
use crate::layer_mix::MixKind;
pub use crate::layer_mix::{LayerMix, MIX_DOMAIN_GLSL};
use crate::lighting_check::LightingCheck;
use crate::resolve::LayerPass;
use crate::{Error, Result};
use glow::HasContext;
use passes::{
    CopyImage, OutputTarget, ResolvePass, host_images_target, mix_pass, single_input_pass,
    split_passes, twin_set,
};
pub use passes::{SECOND_LAYER_DEPTH_FRAG, SECOND_LAYER_FRAG, SECOND_LAYER_SELECT_FRAG};

mod frame;
mod passes;

/// What of the host's G-buffer
/// [`MsaaRetrofit::finish_second_layer`](crate::MsaaRetrofit::finish_second_layer)
/// puts back as the first layer had it
/// ([`RetrofitOptions::restore_first_layer`](crate::RetrofitOptions::restore_first_layer)).
/// [`MsaaRetrofit::begin_second_layer`](crate::MsaaRetrofit::begin_second_layer) copies that much aside and `finish`
/// copies it back; what is not put back holds the second layer afterwards
/// (where a pixel has none, what the second layer's resolve left there).
///
/// Which a host may choose depends on what its passes after lighting read
/// before the next geometry pass overwrites the G-buffer: any colour
/// attachment (screen-space reflections or ambient occlusion, picking from
/// an ID attachment, a debug view): [`FirstLayerRestore::Everything`].
/// Only depth or stencil (transparent objects or particles drawn into the
/// lit image with depth testing, a stencil-masked outline):
/// [`FirstLayerRestore::DepthAndStencil`]. Nothing (the lit image goes
/// straight to tonemapping and post filters that read only colour):
/// [`FirstLayerRestore::Nothing`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FirstLayerRestore {
    /// Colours, depth and stencil (default): the G-buffer afterwards is
    /// bit for bit the one `resolve` wrote.
    #[default]
    Everything,
    /// Depth and stencil only: one copy each way instead of one per
    /// attachment; the colour attachments hold the second layer afterwards.
    DepthAndStencil,
    /// Nothing: no copies; colours, depth and stencil hold the second layer
    /// afterwards.
    Nothing,
}

impl FirstLayerRestore {
    /// Whether the depth and stencil come back.
    pub fn restores_depth(self) -> bool {
        self != FirstLayerRestore::Nothing
    }

    /// Whether the colour attachments come back.
    pub fn restores_colors(self) -> bool {
        self == FirstLayerRestore::Everything
    }
}

/// The stencil value of the pixels the second layer's resolve runs on
/// ([`MsaaRetrofit::second_layer_selection`](crate::MsaaRetrofit::second_layer_selection)).
pub const SECOND_LAYER_SELECTED: u8 = 1;
const SELECTED: u8 = SECOND_LAYER_SELECTED;

/// The second layer's textures, copies and passes (see the module).
#[derive(Debug)]
pub(crate) struct SecondLayer {
    /// Layer 2, in the host's formats, colour `k` for host colour `k`.
    gbuffer: Vec<Texture2d>,
    /// Its coverage `α` (R16F).
    coverage: Texture2d,
    /// Its depth-buffer value (R32F).
    depth: Texture2d,
    /// Its seed sample per pixel (R8UI), for a host whose stencil is copied
    /// from the reference sample: the second lighting sees the seed's.
    reference: Option<Texture2d>,
    /// The pixels its resolve runs on, in a stencil (`DEPTH24_STENCIL8`).
    stencil: Texture2d,
    /// The second layer's resolve, in as many draws as the context's draw
    /// buffers need: each with its colours, the first with the coverage,
    /// depth and seed sample, all with the selection stencil.
    passes: Vec<ResolvePass>,
    /// The host colours the second layer does not carry
    /// ([`RetrofitOptions::second_layer_omits`](crate::RetrofitOptions::second_layer_omits)):
    /// not resolved, and the first layer's value in the host's image during
    /// the second lighting.
    omitted: Vec<usize>,
    /// Layer 2's colours at `Color(k)`, for the copies by blit.
    colours_fbo: Framebuffer,
    /// The first layer's outside flag (R8: a sample lies outside its
    /// cluster), which the first resolve writes where the host's colours
    /// leave it a draw buffer: with it the second resolve runs on those
    /// pixels alone; without, on every pixel.
    flag: Option<Texture2d>,
    /// The first layer, kept while the host lights the second.
    saved: Vec<Texture2d>,
    saved_depth: Texture2d,
    saved_target: Framebuffer,
    /// The host's images, to copy into and out of.
    host_target: Framebuffer,
    /// The same images for `glCopyImageSubData` (colours, then depth),
    /// where the context has it (GL 4.3 or `GL_ARB_copy_image`): a bit-exact
    /// copy of every format; a blit may round a packed depth by a step.
    host_images: Option<Vec<Option<CopyImage>>>,
    /// The host's depth format has stencil, which the second layer's
    /// depth must not overwrite.
    host_stencil: bool,
    /// The host's depth image: a lit output that has it attached shares
    /// the G-buffer's depth.
    host_depth: crate::host::HostImageKind,
    colors: usize,
    depth_bits: u32,
    width: u32,
    height: u32,
    select: FullscreenPass,
    write_depth: FullscreenPass,
    mix_linear: FullscreenPass,
    mix_tonemapped: FullscreenPass,
    mix_srgb: FullscreenPass,
    mix_curve: Option<FullscreenPass>,
    mix: LayerMix,
    /// Counts the pixels with a second layer (coverage above 0) for the
    /// check of the second lighting.
    count: FullscreenPass,
    /// `None` where the host turned the check off
    /// ([`RetrofitOptions::check_second_lighting`](crate::RetrofitOptions::check_second_lighting)).
    check: Option<LightingCheck>,
    /// With the check: counts the pixels with a second layer where the own
    /// target's depth, set to the second layer's for a lighting that tests
    /// the G-buffer's depth, no longer holds it after the second lighting
    /// (a lighting that cleared it lit the second layer as background).
    depth_probe: Option<crate::gl::SamplesPassedQuery>,
    /// The probe's count is not read yet; a count was read once (from then
    /// on a count is read when the GPU has it, or at the next finish).
    probe_pending: bool,
    probe_waited: bool,
    vao: VertexArray,
    output: Option<OutputTarget>,
    /// `begin_second_layer` ran and `finish_second_layer` has not.
    pub(crate) lighting: bool,
    /// The second lighting draws into the crate's own target.
    own_target: bool,
    /// The last `select` marked the selection stencil.
    selected: std::cell::Cell<bool>,
    /// The second layer was resolved since the last `finish_second_layer`.
    pub(crate) resolved: bool,
    /// What `begin` copied of the host's G-buffer aside, so `finish` puts
    /// it back.
    host_saved: FirstLayerRestore,
}

impl GlObject for SecondLayer {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.gbuffer.handles(out);
        self.coverage.handles(out);
        self.depth.handles(out);
        self.reference.handles(out);
        self.stencil.handles(out);
        self.passes.handles(out);
        self.colours_fbo.handles(out);
        self.flag.handles(out);
        self.select.handles(out);
        self.write_depth.handles(out);
        self.saved.handles(out);
        self.saved_depth.handles(out);
        self.saved_target.handles(out);
        self.host_target.handles(out);
        self.mix_linear.handles(out);
        self.mix_tonemapped.handles(out);
        self.mix_srgb.handles(out);
        self.mix_curve.handles(out);
        self.count.handles(out);
        self.check.handles(out);
        self.depth_probe.handles(out);
        self.vao.handles(out);
        self.output.handles(out);
    }
}

impl SecondLayer {
    /// Make the second layer of `host`'s G-buffer and compile its passes.
    pub(crate) fn new(
        gl: &glow::Context,
        host: &HostFramebuffer,
        mix: &LayerMix,
        with_reference: bool,
        check_lighting: bool,
        omitted: &[usize],
    ) -> Result<Self> {
        let (w, h) = host.size();
        let n = host.colors.len() as u32;
        // Its targets attach colour points up to the last draw buffer, so
        // both limits bound them.
        let max_draw_buffers = crate::gl::output_points(gl);
        // The second resolve writes the host's colours, the coverage, the
        // depth and perhaps the seed sample: in as many draws as the draw
        // buffers need.
        let carried: Vec<usize> = (0..host.colors.len())
            .filter(|k| !omitted.contains(k))
            .collect();
        let split = split_passes(&carried, max_draw_buffers, with_reference).ok_or_else(
            || Error::Retrofit {
                attachment: "GL_MAX_DRAW_BUFFERS".into(),
                reason: format!(
                    "two layers need at least {} draw buffers for the second layer's coverage, depth and one colour, the context has {max_draw_buffers}",
                    3 + u32::from(with_reference)
                ),
            },
        )?;
        // The first resolve's outside flag takes the draw buffer after the
        // host's colours (and before the reference index) where one is left.
        let flag_fits = n + 1 + u32::from(with_reference) <= max_draw_buffers;
        Made::build(gl, |made| {
            let texture = |made: &mut Made, label: &str, format: Format| {
                Texture2d::new(gl, label, format, w, h).map(|t| made.keep(t))
            };
            let coverage = texture(made, "second layer coverage", Format::R16f)?;
            let depth = texture(made, "second layer depth", Format::R32f)?;
            let reference = if with_reference {
                Some(texture(made, "second layer seed sample", Format::R8ui)?)
            } else {
                None
            };
            let stencil = texture(made, "second layer selection", Format::Depth24Stencil8)?;
            let mut gbuffer = Vec::with_capacity(host.colors.len());
            for a in &host.colors {
                gbuffer.push(texture(
                    made,
                    &format!("second layer {}", a.point.name()),
                    a.format,
                )?);
            }
            let mut passes = Vec::with_capacity(split.len());
            for (i, colours) in split.iter().enumerate() {
                // The colours this draw writes, then (the first draw) the
                // extras; every draw's target has the selection stencil.
                let mut attachments: Vec<(Attachment, TextureRef)> = colours
                    .iter()
                    .enumerate()
                    .map(|(j, &k)| (Attachment::Color(j as u32), TextureRef::from(&gbuffer[k])))
                    .collect();
                if i == 0 {
                    let c = colours.len() as u32;
                    attachments.push((Attachment::Color(c), TextureRef::from(&coverage)));
                    attachments.push((Attachment::Color(c + 1), TextureRef::from(&depth)));
                    if let Some(r) = &reference {
                        attachments.push((Attachment::Color(c + 2), TextureRef::from(r)));
                    }
                }
                let outputs = attachments.len() as u32;
                attachments.push((Attachment::DepthStencil, TextureRef::from(&stencil)));
                let draw: Vec<Option<u32>> = (0..outputs).map(Some).collect();
                let label = if split.len() == 1 {
                    "second layer".to_string()
                } else {
                    format!("second layer, draw {} of {}", i + 1, split.len())
                };
                let fbo = made.keep(Framebuffer::new(gl, &label, &attachments, &draw)?);
                passes.push(ResolvePass {
                    pass: LayerPass {
                        colors: colours.iter().fold(0u8, |m, &k| m | (1 << k)),
                        extras: i == 0,
                    },
                    colours: colours.len() as u32,
                    fbo,
                });
            }
            let colour_points: Vec<(Attachment, TextureRef)> = gbuffer
                .iter()
                .enumerate()
                .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
                .collect();
            let colours_fbo = made.keep(Framebuffer::new(
                gl,
                "second layer colours",
                &colour_points,
                &(0..n).map(Some).collect::<Vec<_>>(),
            )?);
            let flag = if flag_fits {
                Some(texture(made, "first layer outside flag", Format::R8)?)
            } else {
                None
            };
            let (saved, saved_depth, saved_target) =
                twin_set(gl, made, host, "second layer: first layer kept", &[])?;
            let host_target = made.keep(host_images_target(gl, host)?);
            let version = gl.version();
            let copy_image = (version.major, version.minor) >= (4, 3)
                || gl.supported_extensions().contains("GL_ARB_copy_image");
            // An unsized host format (GL_RGBA, GL_DEPTH_COMPONENT) need not
            // be the sized one ours has, which the copy requires: blit those.
            let host_images = copy_image.then(|| {
                host.colors
                    .iter()
                    .chain([&host.depth])
                    .map(|a| {
                        (a.requested_format == format!("GL_{}", a.format.name()))
                            .then(|| CopyImage::of_host(a))
                    })
                    .collect()
            });
            let select_frag = ("second_layer_select.frag", SECOND_LAYER_SELECT_FRAG);
            let select = made.keep(single_input_pass(
                gl,
                "second layer selection",
                select_frag,
                &[("SELECT_ABOVE", "0.5")],
                "u_value",
                &[("o_unused", 0)],
            )?);
            let count = made.keep(single_input_pass(
                gl,
                "second layer count",
                select_frag,
                &[("SELECT_ABOVE", "0.0")],
                "u_value",
                &[("o_unused", 0)],
            )?);
            let check = if check_lighting {
                Some(made.keep(LightingCheck::new(gl)?))
            } else {
                None
            };
            let depth_probe = if check_lighting {
                Some(made.keep(crate::gl::SamplesPassedQuery::new(gl)?))
            } else {
                None
            };
            let write_depth = made.keep(single_input_pass(
                gl,
                "second layer depth",
                ("second_layer_depth.frag", SECOND_LAYER_DEPTH_FRAG),
                &[],
                "u_layer_depth",
                &[],
            )?);
            let mix_linear = made.keep(mix_pass(gl, MixKind::Linear, None)?);
            let mix_tonemapped = made.keep(mix_pass(gl, MixKind::Tonemapped, None)?);
            let mix_srgb = made.keep(mix_pass(gl, MixKind::SrgbEncoded, None)?);
            let mix_curve = match mix {
                LayerMix::Curve(source) => {
                    Some(made.keep(mix_pass(gl, MixKind::Curve, Some(source))?))
                }
                _ => None,
            };
            let vao = made.keep(VertexArray::new(gl, "second layer passes")?);
            Ok(SecondLayer {
                gbuffer,
                coverage,
                depth,
                reference,
                stencil,
                passes,
                omitted: omitted.to_vec(),
                colours_fbo,
                flag,
                saved,
                saved_depth,
                saved_target,
                host_target,
                host_images,
                host_stencil: host.depth.format.has_stencil(),
                host_depth: host.depth.image,
                colors: host.colors.len(),
                depth_bits: host.depth.format.properties().depth_bits,
                width: w,
                height: h,
                select,
                write_depth,
                mix_linear,
                mix_tonemapped,
                mix_srgb,
                mix_curve,
                mix: mix.clone(),
                count,
                check,
                depth_probe,
                probe_pending: false,
                probe_waited: false,
                vao,
                output: None,
                lighting: false,
                own_target: false,
                host_saved: FirstLayerRestore::Nothing,
                selected: std::cell::Cell::new(false),
                resolved: false,
            })
        })
    }

    /// The crate's own target, while the host lights into it (between
    /// `begin_second_layer_own_target` and `finish_second_layer`).
    pub(crate) fn own_target_framebuffer(&self) -> Option<glow::Framebuffer> {
        let o = self.output.as_ref()?;
        (self.lighting && self.own_target).then(|| o.lit_second_fbo.raw())
    }

    /// What of the own target (made for the last output) someone other
    /// than the crate deleted, in words naming it; `None` while it exists
    /// or was not made.
    pub(crate) fn own_target_deleted(&self, gl: &glow::Context) -> Option<String> {
        let o = self.output.as_ref()?;
        let fbo = o.lit_second_fbo.raw();
        unsafe {
            if !gl.is_framebuffer(fbo) {
                return Some(format!(
                    "the second lighting's own target, framebuffer {} (the one MsaaRetrofit::begin_second_layer_own_target returns)",
                    fbo.0
                ));
            }
            for (what, t) in [
                ("lit second layer", o.lit_second.raw()),
                ("selection stencil", self.stencil.raw()),
            ] {
                if !gl.is_texture(t) {
                    return Some(format!(
                        "the own target's {what} texture {} (attached to framebuffer {}, which begin_second_layer_own_target returns)",
                        t.0, fbo.0
                    ));
                }
            }
        }
        None
    }

    /// The first resolve's outside flag, where it has a draw buffer.
    pub(crate) fn flag(&self) -> Option<&Texture2d> {
        self.flag.as_ref()
    }

    /// Before the second resolve: with the outside flag, clear the coverage
    /// to 0, the depth to the clear depth and the seed sample to 0 (what a
    /// one-cluster pixel holds; its colours are left as they were, which
    /// nothing reads where the coverage is 0) and mark the flagged pixels in
    /// the stencil; the stencil value the resolve is
    /// to run on (`None`: every pixel, without a flag). The caller keeps the
    /// host's state.
    pub(crate) fn select(&self, gl: &glow::Context, clear_depth: f32) -> Result<Option<u8>> {
        self.selected.set(false);
        let Some(flag) = &self.flag else {
            return Ok(None);
        };
        // The extras' draw buffers follow the first draw's colours.
        let n = self.passes[0].colours;
        unsafe {
            self.passes[0].fbo.bind(gl);
            crate::gl::SavedState::prepare_fullscreen_pass(gl);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.clear_buffer_f32_slice(glow::COLOR, n, &[0.0; 4]);
            gl.clear_buffer_f32_slice(glow::COLOR, n + 1, &[clear_depth, 0.0, 0.0, 0.0]);
            if self.reference.is_some() {
                gl.clear_buffer_u32_slice(glow::COLOR, n + 2, &[0; 4]);
            }
            gl.stencil_mask(0xFF);
            gl.clear_buffer_i32_slice(glow::STENCIL, 0, &[0]);
            gl.color_mask(false, false, false, false);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::ALWAYS, i32::from(SELECTED), 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
            self.select.program().bind(gl);
            TextureRef::from(flag).bind(gl, 0);
        }
        self.select.draw(gl, &self.vao);
        unsafe { gl.color_mask(true, true, true, true) };
        check_error(gl, "selecting the second layer's pixels")?;
        self.selected.set(true);
        Ok(Some(SELECTED))
    }

    /// The selection stencil (`DEPTH24_STENCIL8`; its stencil is
    /// [`SECOND_LAYER_SELECTED`] exactly where the last resolve found a
    /// second cluster, 0 elsewhere; its depth is not defined), when the
    /// last resolve marked it (the first resolve had a draw buffer for its
    /// outside flag).
    pub(crate) fn selection(&self) -> Option<&Texture2d> {
        self.selected.get().then_some(&self.stencil)
    }

    /// The second layer's resolve draws: each one's outputs and target
    /// (the first's has the coverage, depth and seed sample, and every
    /// one the selection stencil).
    pub(crate) fn passes(&self) -> impl Iterator<Item = (LayerPass, &Framebuffer)> {
        self.passes.iter().map(|p| (p.pass, &p.fbo))
    }

    /// The coverage texture (R16F, `α` in red).
    pub(crate) fn coverage(&self) -> &Texture2d {
        &self.coverage
    }

    /// Whether the second layer's resolve writes its seed sample.
    pub(crate) fn has_reference(&self) -> bool {
        self.reference.is_some()
    }

    /// The seed sample per pixel, for the host's stencil.
    pub(crate) fn reference(&self) -> Option<&Texture2d> {
        self.reference.as_ref()
    }

    /// Layer 2's colour textures, in host colour order, and its depth-buffer
    /// values (R32F).
    pub(crate) fn gbuffer(&self) -> (&[Texture2d], &Texture2d) {
        (&self.gbuffer, &self.depth)
    }

    /// The bytes the second layer allocates (both G-buffer copies, the
    /// coverage, and the lit copies once an output is known).
    pub(crate) fn bytes(&self) -> u64 {
        let texels = u64::from(self.width) * u64::from(self.height);
        let colours: u64 = self
            .gbuffer
            .iter()
            .map(|t| u64::from(t.format.bytes_per_texel()))
            .sum();
        let ours: u64 = [
            Some(&self.coverage),
            Some(&self.depth),
            Some(&self.stencil),
            Some(&self.saved_depth),
            self.reference.as_ref(),
            self.flag.as_ref(),
        ]
        .into_iter()
        .flatten()
        .map(|t| u64::from(t.format.bytes_per_texel()))
        .sum();
        let lit = self.output.as_ref().map_or(0, |o| {
            2 * u64::from(o.lit_first.format.bytes_per_texel())
                + o.depth_kept
                    .as_ref()
                    .map_or(0, |(t, _)| u64::from(t.format.bytes_per_texel()))
        });
        texels * (2 * colours + ours + lit)
    }
}
