//! The second layer's own passes and targets: its resolve's draws, the
//! copies of the host's images in and out, the mix, and the framebuffers
//! they draw into.

use crate::Result;
use crate::gl::{
    Attachment, Framebuffer, FullscreenPass, GlObject, Handle, Made, ShaderSource, Texture2d,
    TextureRef,
};
use crate::host::{HostAttachment, HostFramebuffer, HostImageKind};
use crate::layer_mix::{MixKind, mix_domain_source};
use crate::lit_output::LitOutput;
use crate::resolve::LayerPass;

/// The mix pass's fragment shader: `second_layer.frag`.
pub const SECOND_LAYER_FRAG: &str = include_str!("second_layer.frag");

/// The pass marking the pixels the second layer's resolve runs on:
/// `second_layer_select.frag`.
pub const SECOND_LAYER_SELECT_FRAG: &str = include_str!("second_layer_select.frag");

/// The pass writing the second layer's depth into the host's:
/// `second_layer_depth.frag`.
pub const SECOND_LAYER_DEPTH_FRAG: &str = include_str!("second_layer_depth.frag");

/// One draw of the second layer's resolve: what it writes and where.
#[derive(Debug)]
pub(super) struct ResolvePass {
    pub(super) pass: LayerPass,
    /// How many colours it writes (the extras' draw buffers follow).
    pub(super) colours: u32,
    pub(super) fbo: Framebuffer,
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
pub(super) fn split_passes(
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
pub(super) struct OutputTarget {
    /// The host's lit target and what its writes mean.
    pub(super) output: LitOutput,
    /// A framebuffer of that image alone, for the mix (the host's may have
    /// other draw buffers); `None` for the default framebuffer.
    pub(super) target: Option<Framebuffer>,
    /// The same image with the second layer's selection stencil: the mix
    /// then draws only where the second resolve ran.
    pub(super) masked: Option<Framebuffer>,
    /// The lit first layer, and the lit second layer: copies of the output
    /// (in [`LitOutput::copy_format`]).
    pub(super) lit_first: Texture2d,
    pub(super) lit_second: Texture2d,
    pub(super) lit_first_fbo: Framebuffer,
    /// The lit second layer's copy with the selection stencil: the
    /// crate's own target for the second lighting
    /// ([`MsaaRetrofit::begin_second_layer_own_target`](crate::MsaaRetrofit::begin_second_layer_own_target)).
    pub(super) lit_second_fbo: Framebuffer,
    /// The output's depth attachment is the G-buffer's depth image (a
    /// lighting whose depth test reads the G-buffer's depth): the own
    /// target's depth then holds the second layer's depth, as the
    /// output's would during a second lighting into it.
    pub(super) shares_depth: bool,
    /// Where the output has a depth of its own (a framebuffer of the
    /// host's whose depth attachment is not the G-buffer's): a copy of it
    /// (its format, at `Attachment::for_depth_format`), taken before the
    /// second lighting into the output and put back after it, so that a
    /// lighting that clears the output's depth leaves it as the first
    /// lighting did.
    pub(super) depth_kept: Option<(Texture2d, Framebuffer)>,
}

impl GlObject for OutputTarget {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.target.handles(out);
        self.masked.handles(out);
        self.lit_first.handles(out);
        self.lit_second.handles(out);
        self.lit_first_fbo.handles(out);
        self.lit_second_fbo.handles(out);
        if let Some((texture, fbo)) = &self.depth_kept {
            texture.handles(out);
            fbo.handles(out);
        }
    }
}

/// A set of G-buffer images the second layer copies between.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Set {
    /// The host's textures.
    Host,
    /// The first layer, kept during the second lighting.
    Saved,
    /// The second layer.
    Second,
}

/// One image for `glCopyImageSubData`: its name, target and layer.
#[derive(Clone, Copy, Debug)]
pub(super) struct CopyImage {
    pub(super) name: glow::Texture,
    pub(super) target: u32,
    pub(super) layer: i32,
}

impl CopyImage {
    pub(super) fn of_host(a: &HostAttachment) -> Self {
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

    pub(super) fn of(t: &Texture2d) -> Self {
        CopyImage {
            name: TextureRef::from(t).raw,
            target: glow::TEXTURE_2D,
            layer: 0,
        }
    }
}

pub(super) fn mix_pass(
    gl: &glow::Context,
    kind: MixKind,
    curve: Option<&str>,
) -> Result<FullscreenPass> {
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
pub(super) fn set_units(gl: &glow::Context, pass: &FullscreenPass, units: &[(&str, i32)]) {
    pass.program().set_at_setup(gl, |p| {
        for &(sampler, unit) in units {
            p.set_i32(gl, sampler, unit);
        }
    });
}

/// A full-screen pass of `body` reading `sampler` from unit 0, with
/// `outputs` bound as given and `defines`.
pub(super) fn single_input_pass(
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
pub(super) fn host_images_target(
    gl: &glow::Context,
    host: &HostFramebuffer,
) -> Result<Framebuffer> {
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
pub(super) fn twin_set(
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
