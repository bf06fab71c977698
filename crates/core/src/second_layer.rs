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

use crate::gl::format::ComponentType;
use crate::gl::{
    Attachment, Format, Framebuffer, FullscreenPass, GlObject, Handle, Made, ShaderSource,
    Texture2d, TextureRef, VertexArray, check_error, destroy_object,
};
use crate::host::{HostAttachment, HostFramebuffer, HostImageKind};
use crate::lighting_check::LightingCheck;
use crate::lit_output::{LitOutput, bind_for_reading};
use crate::profile::StepProfile;
use crate::resolve::LayerPass;
use crate::retrofit::FirstLayerRestore;
use crate::{Error, Result};
use glow::HasContext;

/// The mix pass's fragment shader: `second_layer.frag`.
pub const SECOND_LAYER_FRAG: &str = include_str!("second_layer.frag");

/// The pass marking the pixels the second layer's resolve runs on:
/// `second_layer_select.frag`.
pub const SECOND_LAYER_SELECT_FRAG: &str = include_str!("second_layer_select.frag");

/// The pass writing the second layer's depth into the host's:
/// `second_layer_depth.frag`.
pub const SECOND_LAYER_DEPTH_FRAG: &str = include_str!("second_layer_depth.frag");

/// The stencil value of the pixels the second layer's resolve runs on
/// ([`MsaaRetrofit::second_layer_selection`](crate::MsaaRetrofit::second_layer_selection)).
pub const SECOND_LAYER_SELECTED: u8 = 1;
const SELECTED: u8 = SECOND_LAYER_SELECTED;

/// What the host's lit values mean, and so how the two lit layers are
/// mixed by the second layer's coverage `α` (and the forward target's
/// samples averaged): in the light a screen would emit for them, as far as
/// the declaration says. GL state cannot tell what a host's values mean;
/// declare it (docs/hosts.md says which to declare for the common engine
/// styles).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum LayerMix {
    /// Inferred (default): [`LayerMix::Tonemapped`] for a floating-point
    /// (HDR) output; linear light for an sRGB output the host writes with
    /// `GL_FRAMEBUFFER_SRGB` on (GL decodes and encodes); else
    /// [`LayerMix::Linear`], the values as stored. A host whose 8-bit
    /// output holds display values (no tonemap after it, or its shader
    /// encodes) declares [`LayerMix::SrgbEncoded`]: on every host of the
    /// zoo that mixes closer to the 16x image (docs/hosts.md).
    #[default]
    Auto,
    /// Linear values: `mix(first, second, α)` as the output stores them
    /// (linear light, such as an output a later pass encodes, or values
    /// to be mixed as they are).
    Linear,
    /// sRGB-encoded display values (the host's shader encodes, or writes
    /// display values with no encoding at all, as most LDR programs do;
    /// or an sRGB image written with `GL_FRAMEBUFFER_SRGB` off): decoded,
    /// mixed in linear light, encoded again.
    SrgbEncoded,
    /// In the domain of `T(x) = x / (1 + max3(x))`, mapped back with
    /// `T⁻¹(y) = y / (1 − max3(y))`: a bright layer cannot swamp a dark one,
    /// as after a tonemap (the resolve's `BlendHdr` domain).
    Tonemapped,
    /// In the domain of the host's own tonemap curve: GLSL defining
    /// `vec3 dmsaa_curve(vec3 hdr)` and its inverse
    /// `vec3 dmsaa_curve_inverse(vec3 display)`, with no uniforms.
    Curve(String),
}

/// The blend domain's GLSL, shared with the forward target's resolve:
/// `mix_domain.glsl`.
pub const MIX_DOMAIN_GLSL: &str = include_str!("mix_domain.glsl");

/// The blend domains the mix and the forward resolve are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MixKind {
    Linear,
    Tonemapped,
    Curve,
    SrgbEncoded,
}

impl MixKind {
    pub(crate) fn define(self) -> &'static str {
        match self {
            MixKind::Linear => "MIX_LINEAR",
            MixKind::Tonemapped => "MIX_TONEMAPPED",
            MixKind::Curve => "MIX_CURVE",
            MixKind::SrgbEncoded => "MIX_SRGB_ENCODED",
        }
    }

    /// The domain `mix` blends `output`'s values in, as the crate reads
    /// them (where the host's writes went through GL's sRGB encoding, the
    /// crate's reads are decoded: linear light already).
    pub(crate) fn of(mix: &LayerMix, output: &LitOutput) -> MixKind {
        let float = matches!(output.format.properties().component, ComponentType::Float);
        match mix {
            LayerMix::Curve(_) => MixKind::Curve,
            LayerMix::Tonemapped => MixKind::Tonemapped,
            LayerMix::Linear => MixKind::Linear,
            LayerMix::SrgbEncoded | LayerMix::Auto if output.srgb_writes => MixKind::Linear,
            LayerMix::SrgbEncoded => MixKind::SrgbEncoded,
            LayerMix::Auto if float => MixKind::Tonemapped,
            LayerMix::Auto => MixKind::Linear,
        }
    }
}

/// The shader source up to the blend domain's functions: its define, the
/// host's curve for [`MixKind::Curve`], `mix_domain.glsl`.
pub(crate) fn mix_domain_source(kind: MixKind, curve: Option<&str>) -> ShaderSource {
    let mut source = ShaderSource::new().define(kind.define(), "1");
    if let (MixKind::Curve, Some(curve)) = (kind, curve) {
        source = source.part("LayerMix::Curve", curve);
    }
    source.part("mix_domain.glsl", MIX_DOMAIN_GLSL)
}

/// One draw of the second layer's resolve: what it writes and where.
#[derive(Debug)]
struct ResolvePass {
    pass: LayerPass,
    /// How many colours it writes (the extras' draw buffers follow).
    colours: u32,
    fbo: Framebuffer,
}

impl GlObject for ResolvePass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.fbo.handles(out);
    }
}

/// The host colours (of `carried`, in order) each draw of the second
/// layer's resolve writes: the first draw also writes the coverage, the
/// depth and (`with_reference`) the seed sample, so it takes as many
/// colours as leave room for them in `draw_buffers`; each further draw
/// takes up to `draw_buffers` colours. `None` where not even the first
/// draw fits one colour.
fn split_passes(
    carried: &[usize],
    draw_buffers: u32,
    with_reference: bool,
) -> Option<Vec<Vec<usize>>> {
    let extras = 2 + usize::from(with_reference);
    let buffers = draw_buffers as usize;
    let first = buffers
        .checked_sub(extras)
        .filter(|&f| f >= 1 || carried.is_empty())?;
    let (head, mut rest) = carried.split_at(carried.len().min(first));
    let mut passes = vec![head.to_vec()];
    while !rest.is_empty() {
        let (chunk, tail) = rest.split_at(rest.len().min(buffers));
        passes.push(chunk.to_vec());
        rest = tail;
    }
    Some(passes)
}

/// The lit output's colour image, as the second layer reads and writes it.
#[derive(Debug)]
struct OutputTarget {
    /// The host's lit target and what its writes mean.
    output: LitOutput,
    /// A framebuffer of that image alone, for the mix (the host's may have
    /// other draw buffers); `None` for the default framebuffer.
    target: Option<Framebuffer>,
    /// The same image with the second layer's selection stencil: the mix
    /// then draws only where the second resolve ran.
    masked: Option<Framebuffer>,
    /// The lit first layer, and the lit second layer: copies of the output
    /// (in [`LitOutput::copy_format`]).
    lit_first: Texture2d,
    lit_second: Texture2d,
    lit_first_fbo: Framebuffer,
    /// The lit second layer's copy with the selection stencil: the
    /// crate's own target for the second lighting
    /// ([`MsaaRetrofit::begin_second_layer_own_target`](crate::MsaaRetrofit::begin_second_layer_own_target)).
    lit_second_fbo: Framebuffer,
}

impl GlObject for OutputTarget {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.target.handles(out);
        self.masked.handles(out);
        self.lit_first.handles(out);
        self.lit_second.handles(out);
        self.lit_first_fbo.handles(out);
        self.lit_second_fbo.handles(out);
    }
}

/// A set of G-buffer images the second layer copies between.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Set {
    /// The host's textures.
    Host,
    /// The first layer, kept during the second lighting.
    Saved,
    /// The second layer.
    Second,
}

/// One image for `glCopyImageSubData`: its name, target and layer.
#[derive(Clone, Copy, Debug)]
struct CopyImage {
    name: glow::Texture,
    target: u32,
    layer: i32,
}

impl CopyImage {
    fn of_host(a: &HostAttachment) -> Self {
        let (name, target, layer) = match a.image {
            HostImageKind::Texture2d(t) => (t, glow::TEXTURE_2D, 0),
            HostImageKind::TextureLayer { texture, layer } => {
                (texture, glow::TEXTURE_2D_ARRAY, layer as i32)
            }
            HostImageKind::Renderbuffer(rb) => (glow::NativeTexture(rb.0), glow::RENDERBUFFER, 0),
        };
        CopyImage {
            name,
            target,
            layer,
        }
    }

    fn of(t: &Texture2d) -> Self {
        CopyImage {
            name: TextureRef::from(t).raw,
            target: glow::TEXTURE_2D,
            layer: 0,
        }
    }
}

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
        self.vao.handles(out);
        self.output.handles(out);
    }
}

fn mix_pass(gl: &glow::Context, kind: MixKind, curve: Option<&str>) -> Result<FullscreenPass> {
    let fragment = mix_domain_source(kind, curve).part("second_layer.frag", SECOND_LAYER_FRAG);
    let pass = FullscreenPass::new(
        gl,
        &format!("second layer mix ({})", kind.define()),
        &fragment,
        &[("o_color", 0)],
    )?;
    set_units(
        gl,
        &pass,
        &[("u_first", 0), ("u_second", 1), ("u_coverage", 2)],
    );
    Ok(pass)
}

/// Point `pass`'s samplers at their texture units, once, at set-up.
fn set_units(gl: &glow::Context, pass: &FullscreenPass, units: &[(&str, i32)]) {
    pass.program().set_at_setup(gl, |p| {
        for &(sampler, unit) in units {
            p.set_i32(gl, sampler, unit);
        }
    });
}

/// A full-screen pass of `body` reading `sampler` from unit 0, with
/// `outputs` bound as given and `defines`.
fn single_input_pass(
    gl: &glow::Context,
    label: &str,
    (name, body): (&str, &str),
    defines: &[(&str, &str)],
    sampler: &str,
    outputs: &[(&str, u32)],
) -> Result<FullscreenPass> {
    let mut source = ShaderSource::new();
    for (define, value) in defines {
        source = source.define(define, value);
    }
    let pass = FullscreenPass::new(gl, label, &source.part(name, body), outputs)?;
    set_units(gl, &pass, &[(sampler, 0)]);
    Ok(pass)
}

/// A framebuffer over the host's colour images at `Color(k)` and its depth
/// image, for the copies.
fn host_images_target(gl: &glow::Context, host: &HostFramebuffer) -> Result<Framebuffer> {
    let (attachments, images) = host.images();
    let draw: Vec<Option<u32>> = (0..host.colors.len() as u32).map(Some).collect();
    Framebuffer::with_host_images(
        gl,
        "second layer copies (host images)",
        &attachments,
        &images,
        &draw,
    )
}

/// Textures of the host's formats and a framebuffer over them (`extra`
/// colour attachments after the host's).
fn twin_set(
    gl: &glow::Context,
    made: &mut Made,
    host: &HostFramebuffer,
    what: &str,
    extra: &[(Attachment, TextureRef)],
) -> Result<(Vec<Texture2d>, Texture2d, Framebuffer)> {
    let (w, h) = host.size();
    let mut textures = Vec::with_capacity(host.colors.len());
    for a in &host.colors {
        textures.push(made.keep(Texture2d::new(
            gl,
            &format!("{what} {}", a.point.name()),
            a.format,
            w,
            h,
        )?));
    }
    let depth = made.keep(Texture2d::new(
        gl,
        &format!("{what} depth"),
        host.depth.format,
        w,
        h,
    )?);
    let mut attachments: Vec<(Attachment, TextureRef)> = textures
        .iter()
        .enumerate()
        .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
        .collect();
    attachments.extend_from_slice(extra);
    attachments.push((host.depth.point, TextureRef::from(&depth)));
    let draw: Vec<Option<u32>> = (0..(host.colors.len() + extra.len()) as u32)
        .map(Some)
        .collect();
    let fbo = made.keep(Framebuffer::new(gl, what, &attachments, &draw)?);
    Ok((textures, depth, fbo))
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
        let max_draw_buffers = crate::retrofit::output_points(gl);
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
        let lit = self
            .output
            .as_ref()
            .map_or(0, |o| 2 * u64::from(o.lit_first.format.bytes_per_texel()));
        texels * (2 * colours + ours + lit)
    }

    /// Copy colour attachment `k` (or depth, for `None`, with the stencil
    /// when `with_stencil`) of `from` into `to`.
    fn copy(
        &self,
        gl: &glow::Context,
        from: &Framebuffer,
        to: &Framebuffer,
        k: Option<usize>,
        with_stencil: bool,
    ) {
        let depth_bits = if with_stencil && self.host_stencil {
            glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT
        } else {
            glow::DEPTH_BUFFER_BIT
        };
        let (w, h) = (self.width as i32, self.height as i32);
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(from.raw()));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(to.raw()));
            match k {
                Some(k) => {
                    gl.read_buffer(glow::COLOR_ATTACHMENT0 + k as u32);
                    let mut draw = vec![glow::NONE; k + 1];
                    draw[k] = glow::COLOR_ATTACHMENT0 + k as u32;
                    gl.draw_buffers(&draw);
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
                }
                None => gl.blit_framebuffer(0, 0, w, h, 0, 0, w, h, depth_bits, glow::NEAREST),
            }
        }
    }

    /// The images of a set: the host's (`None`), or one of ours.
    fn images(&self, set: Set) -> Option<Vec<Option<CopyImage>>> {
        let ours = |textures: &[Texture2d], depth: &Texture2d| {
            textures
                .iter()
                .chain([depth])
                .map(|t| Some(CopyImage::of(t)))
                .collect()
        };
        match set {
            Set::Host => self.host_images.clone(),
            Set::Saved => self
                .host_images
                .as_ref()
                .map(|_| ours(&self.saved, &self.saved_depth)),
            Set::Second => self.host_images.as_ref().map(|_| {
                self.gbuffer
                    .iter()
                    .map(|t| Some(CopyImage::of(t)))
                    .collect()
            }),
        }
    }

    fn framebuffer(&self, set: Set) -> &Framebuffer {
        match set {
            Set::Host => &self.host_target,
            Set::Saved => &self.saved_target,
            Set::Second => &self.colours_fbo,
        }
    }

    /// Copy the colours (with `colors`) and depth of `from` into `to`: with
    /// `glCopyImageSubData` where the context has it, bit for bit (a
    /// packed depth-stencil's stencil with its depth, unless `keep_stencil`,
    /// when its depth alone is blitted), else by blits (the stencil with the
    /// depth unless `keep_stencil`).
    fn copy_set(&self, gl: &glow::Context, from: Set, to: Set, colors: bool, keep_stencil: bool) {
        let (src, dst) = (self.images(from), self.images(to));
        let (a, b) = (self.framebuffer(from), self.framebuffer(to));
        let (w, h) = (self.width as i32, self.height as i32);
        unsafe {
            // Bits, not colours: no sRGB decode or encode on the way.
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
        }
        let mut blitted = false;
        for k in 0..=self.colors {
            let depth = k == self.colors;
            if !depth && !colors {
                continue;
            }
            // The second layer's depth comes through its own pass.
            if depth && (self.depth_bits == 0 || from == Set::Second || to == Set::Second) {
                continue;
            }
            // An attachment the second layer does not carry keeps the first
            // layer's value in the host's image.
            if !depth && from == Set::Second && self.omitted.contains(&k) {
                continue;
            }
            let image = |set: &Option<Vec<Option<CopyImage>>>| {
                set.as_ref()
                    .and_then(|images| images.get(k).copied().flatten())
            };
            match (image(&src), image(&dst)) {
                (Some(s), Some(d)) if !(depth && keep_stencil && self.host_stencil) => unsafe {
                    gl.copy_image_sub_data(
                        s.name, s.target, 0, 0, 0, s.layer, d.name, d.target, 0, 0, 0, d.layer, w,
                        h, 1,
                    );
                },
                _ => {
                    self.copy(gl, a, b, (!depth).then_some(k), !keep_stencil);
                    blitted |= !depth;
                }
            }
        }
        if blitted {
            // A blit set the target's draw buffers to one colour: all again.
            let all: Vec<u32> = (0..self.colors as u32)
                .map(|k| glow::COLOR_ATTACHMENT0 + k)
                .collect();
            unsafe {
                gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(b.raw()));
                gl.draw_buffers(&all);
            }
        }
    }

    /// The output's colour image and the lit copies, made again when the
    /// output, or the way the host writes it, changed.
    fn output_for(
        &mut self,
        gl: &glow::Context,
        host: Option<glow::Framebuffer>,
        framebuffer_srgb: bool,
    ) -> Result<()> {
        if self
            .output
            .as_ref()
            .is_some_and(|o| o.output.same(host, framebuffer_srgb))
        {
            return Ok(());
        }
        if let Some(old) = self.output.take() {
            destroy_object(gl, old);
        }
        let output = LitOutput::inspect(gl, host, framebuffer_srgb, (self.width, self.height))?;
        let (w, h) = (self.width, self.height);
        let format = output.copy_format();
        let stencil = (Attachment::DepthStencil, TextureRef::from(&self.stencil));
        let made = Made::build(gl, |made| {
            // The host's output image, alone and with the selection stencil
            // that masks the mix.
            let target = output
                .framebuffer(gl, "second layer mix target (host output)", &[])?
                .map(|f| made.keep(f));
            let masked = output
                .framebuffer(
                    gl,
                    "second layer mix target (host output, selection stencil)",
                    &[stencil],
                )?
                .map(|f| made.keep(f));
            let lit_first = made.keep(Texture2d::new(gl, "lit first layer", format, w, h)?);
            let lit_second = made.keep(Texture2d::new(gl, "lit second layer", format, w, h)?);
            let lit_first_fbo = made.keep(Framebuffer::new(
                gl,
                "lit first layer",
                &[(Attachment::Color(0), TextureRef::from(&lit_first))],
                &[Some(0)],
            )?);
            let lit_second_fbo = made.keep(Framebuffer::new(
                gl,
                "lit second layer (the second lighting's own target)",
                &[
                    (Attachment::Color(0), TextureRef::from(&lit_second)),
                    stencil,
                ],
                &[Some(0)],
            )?);
            Ok::<_, Error>((
                target,
                masked,
                lit_first,
                lit_second,
                lit_first_fbo,
                lit_second_fbo,
            ))
        })?;
        let (target, masked, lit_first, lit_second, lit_first_fbo, lit_second_fbo) = made;
        self.output = Some(OutputTarget {
            output,
            target,
            masked,
            lit_first,
            lit_second,
            lit_first_fbo,
            lit_second_fbo,
        });
        Ok(())
    }

    /// Copy the output's lit colour into `first` (or the second copy).
    fn keep_lit(&self, gl: &glow::Context, first: bool) {
        let Some(o) = &self.output else {
            return;
        };
        let (w, h) = (self.width as i32, self.height as i32);
        let to = if first {
            &o.lit_first_fbo
        } else {
            &o.lit_second_fbo
        };
        unsafe {
            // Bits as stored (the copies have the image's encoding only
            // where the host's writes were encoded).
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            bind_for_reading(gl, o.target.as_ref());
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(to.raw()));
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
        }
    }

    /// Count the pixels with a second layer, for the check of the second
    /// lighting (after the second resolve; the caller keeps the host's
    /// state). A failed check of the last frame's lighting is returned.
    pub(crate) fn count_selected(&mut self, gl: &glow::Context) -> Result<()> {
        let (count, vao, coverage) = (&self.count, &self.vao, &self.coverage);
        let target = &self.passes[0].fbo;
        let Some(check) = &mut self.check else {
            return Ok(());
        };
        check.count_selected(gl, || unsafe {
            count.begin(gl, target);
            gl.disable(glow::STENCIL_TEST);
            gl.color_mask(false, false, false, false);
            TextureRef::from(coverage).bind(gl, 0);
            count.draw(gl, vao);
            gl.color_mask(true, true, true, true);
        })
    }

    /// The crate's own target for the second lighting, prepared: the
    /// lit second layer's copy (cleared to the host's clear colour) with
    /// the selection stencil (its depth cleared to the host's clear depth;
    /// its stencil [`SECOND_LAYER_SELECTED`] on every pixel where no
    /// selection was made). The caller keeps the host's state.
    fn prepare_own_target(&self, gl: &glow::Context) -> Option<glow::Framebuffer> {
        let o = self.output.as_ref()?;
        unsafe {
            let mut colour = [0.0f32; 4];
            gl.get_parameter_f32_slice(glow::COLOR_CLEAR_VALUE, &mut colour);
            let depth = gl.get_parameter_f32(glow::DEPTH_CLEAR_VALUE);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(o.lit_second_fbo.raw()));
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.clear_buffer_f32_slice(glow::COLOR, 0, &colour);
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[depth]);
            if !self.selected.get() {
                gl.stencil_mask(0xFF);
                gl.clear_buffer_i32_slice(glow::STENCIL, 0, &[i32::from(SELECTED)]);
            }
        }
        Some(o.lit_second_fbo.raw())
    }

    /// Keep the lit first layer from `output` and put the second layer into
    /// the host's textures (the caller saves the host's state); first copy
    /// aside what `restore` says of the host's G-buffer, for `finish` to
    /// put back.
    pub(crate) fn begin(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        restore: FirstLayerRestore,
        own_target: bool,
        profile: &mut StepProfile,
    ) -> Result<Option<glow::Framebuffer>> {
        if self.lighting {
            return Err(Error::invalid(
                "begin_second_layer was called twice: call finish_second_layer after the second lighting",
            ));
        }
        if !self.resolved {
            return Err(Error::invalid(
                "begin_second_layer needs this frame's resolve first (MsaaRetrofit::resolve)",
            ));
        }
        // Whether the host's lighting wrote through the sRGB encoding, as
        // it left GL_FRAMEBUFFER_SRGB (read before the crate touches it).
        let framebuffer_srgb = unsafe { gl.is_enabled(glow::FRAMEBUFFER_SRGB) };
        self.output_for(gl, output, framebuffer_srgb)?;
        profile.time(gl, "second layer: keep lit first layer", || {
            self.keep_lit(gl, true)
        });
        match restore {
            FirstLayerRestore::Everything => {
                profile.time(gl, "second layer: save host G-buffer", || {
                    self.copy_set(gl, Set::Host, Set::Saved, true, false)
                })
            }
            FirstLayerRestore::DepthAndStencil => {
                profile.time(gl, "second layer: save host depth", || {
                    self.copy_set(gl, Set::Host, Set::Saved, false, false)
                })
            }
            FirstLayerRestore::Nothing => {}
        }
        self.host_saved = restore;
        // The host's stencil stays: its lighting may test it.
        profile.time(gl, "second layer: copy in", || {
            self.copy_set(gl, Set::Second, Set::Host, true, true)
        });
        profile.time(gl, "second layer: depth into host", || {
            self.depth_into_host(gl)
        });
        let own = if own_target {
            self.prepare_own_target(gl)
        } else {
            None
        };
        check_error(gl, "keeping the first layer and copying in the second")?;
        self.lighting = true;
        self.own_target = own.is_some();
        Ok(own)
    }

    /// The host's first lighting is over (or the frame went on without
    /// it): the crate's own drawing is not counted as the host's.
    pub(crate) fn end_first_lighting(&mut self, gl: &glow::Context) {
        if let Some(check) = &mut self.check {
            check.end_first(gl);
        }
    }

    /// The host's second lighting starts: the check counts what it draws.
    pub(crate) fn lighting_begins(&mut self, gl: &glow::Context) {
        if let Some(check) = &mut self.check {
            check.lighting_begins(gl);
        }
    }

    /// A `begin` that failed after the count began: no lighting follows.
    pub(crate) fn abandon_check(&mut self, gl: &glow::Context) {
        if let Some(check) = &mut self.check {
            check.abandon(gl);
        }
    }

    /// Mix the two lit layers into the output and, where `begin` saved it,
    /// put the first layer back into the host's textures (the caller saves
    /// the host's state).
    pub(crate) fn finish(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        profile: &mut StepProfile,
    ) -> Result<()> {
        if !self.lighting {
            return Err(Error::invalid(
                "finish_second_layer without begin_second_layer",
            ));
        }
        if self.output.as_ref().map(|o| o.output.host) != Some(output) {
            return Err(Error::invalid(
                "finish_second_layer was given another output than begin_second_layer",
            ));
        }
        self.lighting = false;
        self.resolved = false;
        let checked = match &mut self.check {
            Some(check) => check.lighting_ends(gl),
            None => Ok(()),
        };
        if !self.own_target {
            profile.time(gl, "second layer: keep lit second layer", || {
                self.keep_lit(gl, false)
            });
        }
        profile.time(gl, "second layer: mix", || self.draw_mix(gl))?;
        // Depth and stencil as they were before the second lighting.
        match self.host_saved {
            FirstLayerRestore::Everything => {
                profile.time(gl, "second layer: restore host G-buffer", || {
                    self.copy_set(gl, Set::Saved, Set::Host, true, false)
                })
            }
            FirstLayerRestore::DepthAndStencil => {
                profile.time(gl, "second layer: restore host depth", || {
                    self.copy_set(gl, Set::Saved, Set::Host, false, false)
                })
            }
            FirstLayerRestore::Nothing => {}
        }
        check_error(gl, "mixing the two lit layers")?;
        checked
    }

    /// The second layer's depth into the host's depth attachment (its
    /// stencil untouched).
    fn depth_into_host(&self, gl: &glow::Context) {
        if self.depth_bits == 0 {
            return;
        }
        unsafe {
            self.host_target.bind(gl);
            crate::gl::SavedState::prepare_fullscreen_pass(gl);
            gl.color_mask(false, false, false, false);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::ALWAYS);
            gl.depth_mask(true);
            self.write_depth.program().bind(gl);
            TextureRef::from(&self.depth).bind(gl, 0);
        }
        self.write_depth.draw(gl, &self.vao);
        unsafe { gl.color_mask(true, true, true, true) };
    }

    fn draw_mix(&self, gl: &glow::Context) -> Result<()> {
        let Some(o) = &self.output else {
            return Ok(());
        };
        let pass = match (MixKind::of(&self.mix, &o.output), &self.mix_curve) {
            (MixKind::Curve, Some(curve)) => curve,
            (MixKind::Tonemapped, _) => &self.mix_tonemapped,
            (MixKind::SrgbEncoded, _) => &self.mix_srgb,
            _ => &self.mix_linear,
        };
        // sRGB outputs the host wrote through the encoding: read decoded,
        // mixed in linear light, encoded again; any other: as stored.
        let srgb = o.output.srgb_writes;
        // With the selection stencil and an image of the host's: the first
        // layer back everywhere by a copy, then the mix only where the second
        // resolve ran (a superset of the pixels with coverage above 0).
        if let (Some(masked), Some(target), true) = (&o.masked, &o.target, self.selected.get()) {
            let (w, h) = (self.width as i32, self.height as i32);
            unsafe {
                gl.disable(glow::FRAMEBUFFER_SRGB);
                gl.disable(glow::SCISSOR_TEST);
                gl.color_mask(true, true, true, true);
                gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(o.lit_first_fbo.raw()));
                gl.read_buffer(glow::COLOR_ATTACHMENT0);
                gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(target.raw()));
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
                pass.begin(gl, masked);
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::EQUAL, i32::from(SELECTED), 0xFF);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
                gl.stencil_mask(0);
                set_srgb(gl, srgb);
                TextureRef::from(&o.lit_first).bind(gl, 0);
                TextureRef::from(&o.lit_second).bind(gl, 1);
                TextureRef::from(&self.coverage).bind(gl, 2);
            }
            pass.draw(gl, &self.vao);
            return Ok(());
        }
        unsafe {
            match &o.target {
                Some(t) => {
                    pass.begin(gl, t);
                }
                None => {
                    gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                    crate::gl::SavedState::prepare_fullscreen_pass(gl);
                    gl.disable(glow::DEPTH_TEST);
                    gl.viewport(0, 0, self.width as i32, self.height as i32);
                    pass.program().bind(gl);
                }
            }
            gl.disable(glow::STENCIL_TEST);
            set_srgb(gl, srgb);
            TextureRef::from(&o.lit_first).bind(gl, 0);
            TextureRef::from(&o.lit_second).bind(gl, 1);
            TextureRef::from(&self.coverage).bind(gl, 2);
        }
        pass.draw(gl, &self.vao);
        Ok(())
    }
}

/// `GL_FRAMEBUFFER_SRGB` on or off.
pub(crate) fn set_srgb(gl: &glow::Context, on: bool) {
    unsafe {
        if on {
            gl.enable(glow::FRAMEBUFFER_SRGB);
        } else {
            gl.disable(glow::FRAMEBUFFER_SRGB);
        }
    }
}
