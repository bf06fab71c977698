//! The two-line integration: multisampled twins of a host engine's G-buffer,
//! resolved back into the host's own textures.
//!
//! ```text
//! geometry pass:  gl.bind_framebuffer(FRAMEBUFFER, Some(msaa.framebuffer()));   // instead of the host's
//! after it:       msaa.resolve(&gl, &params)?;                                    // writes the host's textures
//! ```
//! The host's model and lighting shaders do not change: the twins have the
//! same formats, attachment points and draw-buffer mapping as the host's FBO.

use crate::gbuffer::{MemoryBudget, MultisampleTwin, TwinSpec, budget_twins};
use crate::gl::{Attachment, Format, Framebuffer, TextureRef, check_error};
use crate::resolve::{KeySource, ResolveInputs, ResolveParams, ResolveRule, Resolver, Schedule};
use crate::{Error, Result};
use glow::HasContext;

/// How a host G-buffer is to be multisampled and resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct RetrofitOptions {
    /// Requested samples per pixel (the driver's real count is used and reported).
    pub samples: u32,
    /// Rules for colour attachments by attachment number (`GL_COLOR_ATTACHMENTi`);
    /// the others take their format's default (blend; select for integers).
    pub rules: Vec<(u32, ResolveRule)>,
    /// The colour attachment number holding view-space position, whose `−z`
    /// is the depth key; `None` linearises the depth attachment instead.
    pub position_attachment: Option<u32>,
}

impl Default for RetrofitOptions {
    fn default() -> Self {
        RetrofitOptions {
            samples: 4,
            rules: Vec::new(),
            position_attachment: None,
        }
    }
}

/// One texture attachment of the host's framebuffer, as introspected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostAttachment {
    /// Attachment point.
    pub point: Attachment,
    /// The host's texture.
    pub texture: glow::Texture,
    /// Its internal format.
    pub format: Format,
    /// Width of level 0.
    pub width: u32,
    /// Height of level 0.
    pub height: u32,
}

impl HostAttachment {
    fn texture_ref(&self) -> TextureRef {
        TextureRef {
            raw: self.texture,
            target: glow::TEXTURE_2D,
            format: self.format,
            width: self.width,
            height: self.height,
            samples: 1,
        }
    }
}

/// What a host framebuffer holds.
#[derive(Clone, Debug, PartialEq)]
pub struct HostFramebuffer {
    /// The host's FBO.
    pub fbo: glow::Framebuffer,
    /// Colour attachments, by ascending attachment number.
    pub colors: Vec<HostAttachment>,
    /// The depth (or depth-stencil) attachment.
    pub depth: HostAttachment,
    /// Draw buffer `i` → colour attachment number (`None` for `GL_NONE`).
    pub draw_buffers: Vec<Option<u32>>,
}

impl HostFramebuffer {
    /// Width and height (all attachments agree).
    pub fn size(&self) -> (u32, u32) {
        (self.depth.width, self.depth.height)
    }
}

fn attachment_param(gl: &glow::Context, point: u32, pname: u32) -> i32 {
    unsafe { gl.get_framebuffer_attachment_parameter_i32(glow::FRAMEBUFFER, point, pname) }
}

fn introspect_point(gl: &glow::Context, point: Attachment) -> Result<Option<HostAttachment>> {
    let name = point.name();
    let e = point.gl_enum();
    let kind = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE) as u32;
    match kind {
        glow::NONE => return Ok(None),
        glow::TEXTURE => {}
        glow::RENDERBUFFER => {
            return Err(Error::Retrofit {
                attachment: name,
                reason: "it is a renderbuffer; the resolve must read the samples in a shader, so the host needs a texture here".into(),
            });
        }
        other => {
            return Err(Error::Retrofit {
                attachment: name,
                reason: format!("unexpected object type 0x{other:04X}"),
            });
        }
    }
    let raw = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME) as u32;
    let level = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_TEXTURE_LEVEL);
    let layered = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_LAYERED);
    let _ = check_error(gl, "reading attachment parameters");
    let texture = std::num::NonZeroU32::new(raw)
        .map(glow::NativeTexture)
        .ok_or_else(|| Error::Retrofit {
            attachment: name.clone(),
            reason: "the driver reports texture 0".into(),
        })?;
    if level != 0 || layered != 0 {
        return Err(Error::Retrofit {
            attachment: name,
            reason: format!(
                "texture {raw} is attached at level {level}{}; only level 0 of a 2D texture is supported",
                if layered != 0 { " and layered" } else { "" }
            ),
        });
    }
    // Binding to TEXTURE_2D fails for any other target: that is how a 2D texture is told apart.
    let _ = check_error(gl, "before introspecting a texture");
    let (internal, width, height) = unsafe {
        gl.bind_texture(glow::TEXTURE_2D, Some(texture));
        let ok = gl.get_error() == glow::NO_ERROR;
        let v = (
            gl.get_tex_level_parameter_i32(glow::TEXTURE_2D, 0, glow::TEXTURE_INTERNAL_FORMAT),
            gl.get_tex_level_parameter_i32(glow::TEXTURE_2D, 0, glow::TEXTURE_WIDTH),
            gl.get_tex_level_parameter_i32(glow::TEXTURE_2D, 0, glow::TEXTURE_HEIGHT),
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
        if !ok {
            return Err(Error::Retrofit {
                attachment: name,
                reason: format!(
                    "texture {raw} is not a GL_TEXTURE_2D (multisampled, array or cube textures cannot be retrofitted)"
                ),
            });
        }
        v
    };
    let format =
        Format::from_internal_format(internal as u32).ok_or_else(|| Error::UnsupportedFormat {
            attachment: name.clone(),
            format: format!("0x{internal:04X}"),
            reason: format!(
                "not a format the resolve knows; supported: {}",
                Format::ALL
                    .iter()
                    .map(|f| f.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?;
    Ok(Some(HostAttachment {
        point,
        texture,
        format,
        width: width.max(0) as u32,
        height: height.max(0) as u32,
    }))
}

/// Read a host framebuffer's attachments, formats, sizes and draw-buffer
/// mapping. The host's framebuffer binding is left as it was.
pub fn introspect(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<HostFramebuffer> {
    let previous = unsafe { gl.get_parameter_i32(glow::FRAMEBUFFER_BINDING) };
    let previous_tex = unsafe { gl.get_parameter_i32(glow::TEXTURE_BINDING_2D) };
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
    let result = introspect_bound(gl, fbo);
    unsafe {
        gl.bind_framebuffer(
            glow::FRAMEBUFFER,
            std::num::NonZeroU32::new(previous as u32).map(glow::NativeFramebuffer),
        );
        gl.bind_texture(
            glow::TEXTURE_2D,
            std::num::NonZeroU32::new(previous_tex as u32).map(glow::NativeTexture),
        );
    }
    result
}

fn introspect_bound(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<HostFramebuffer> {
    let max_colors =
        unsafe { gl.get_parameter_i32(glow::MAX_COLOR_ATTACHMENTS) }.clamp(1, 32) as u32;
    let max_draw = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) }.clamp(1, 32) as u32;
    let mut colors = Vec::new();
    for i in 0..max_colors {
        if let Some(a) = introspect_point(gl, Attachment::Color(i))? {
            colors.push(a);
        }
    }
    // Querying GL_DEPTH_STENCIL_ATTACHMENT is an error when depth and stencil
    // differ; read the depth point, and call it depth-stencil when the same
    // texture also sits at the stencil point.
    let depth = introspect_point(gl, Attachment::Depth)?.map(|mut a| {
        let stencil_name = attachment_param(
            gl,
            glow::STENCIL_ATTACHMENT,
            glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME,
        );
        if a.format.has_stencil() && stencil_name as u32 == a.texture.0.get() {
            a.point = Attachment::DepthStencil;
        }
        a
    });
    let depth = depth.ok_or_else(|| Error::Retrofit {
        attachment: "GL_DEPTH_ATTACHMENT".into(),
        reason: "the host framebuffer has no depth attachment; the resolve needs per-sample depth"
            .into(),
    })?;
    if !depth.format.is_depth() {
        return Err(Error::UnsupportedFormat {
            attachment: "GL_DEPTH_ATTACHMENT".into(),
            format: depth.format.name().into(),
            reason: "not a depth format".into(),
        });
    }
    if colors.is_empty() {
        return Err(Error::Retrofit {
            attachment: "GL_COLOR_ATTACHMENT0".into(),
            reason: "the host framebuffer has no colour attachments".into(),
        });
    }
    if colors.len() > crate::resolve::MAX_ATTACHMENTS {
        return Err(Error::Retrofit {
            attachment: colors[crate::resolve::MAX_ATTACHMENTS].point.name(),
            reason: format!(
                "at most {} colour attachments are supported",
                crate::resolve::MAX_ATTACHMENTS
            ),
        });
    }
    for a in &colors {
        if (a.width, a.height) != (depth.width, depth.height) {
            return Err(Error::Retrofit {
                attachment: a.point.name(),
                reason: format!(
                    "it is {}x{} but the depth attachment is {}x{}; all attachments must have one size",
                    a.width, a.height, depth.width, depth.height
                ),
            });
        }
        if a.format.is_depth() {
            return Err(Error::UnsupportedFormat {
                attachment: a.point.name(),
                format: a.format.name().into(),
                reason: "a depth format on a colour attachment".into(),
            });
        }
    }
    let mut draw_buffers = Vec::new();
    for i in 0..max_draw {
        let b = unsafe { gl.get_parameter_i32(glow::DRAW_BUFFER0 + i) } as u32;
        draw_buffers.push(
            (glow::COLOR_ATTACHMENT0..glow::COLOR_ATTACHMENT0 + 32)
                .contains(&b)
                .then(|| b - glow::COLOR_ATTACHMENT0),
        );
    }
    while draw_buffers.last() == Some(&None) {
        draw_buffers.pop();
    }
    check_error(gl, "introspecting the host framebuffer")?;
    Ok(HostFramebuffer {
        fbo,
        colors,
        depth,
        draw_buffers,
    })
}

/// A host G-buffer retrofitted with MSAA: multisampled twins to draw into and
/// a resolve that writes the host's original textures.
#[derive(Debug)]
pub struct MsaaRetrofit {
    host: HostFramebuffer,
    options: RetrofitOptions,
    twin: MultisampleTwin,
    target: Framebuffer,
    rules: Vec<ResolveRule>,
    key: KeySource,
    resolver: Resolver,
    /// The memory budget of [`MsaaRetrofit::with_budget`], applied again on
    /// every rebuild.
    budget: Option<MemoryBudget>,
    /// What the budget did (a stepped-down sample count), one line each.
    warnings: Vec<String>,
}

impl MsaaRetrofit {
    /// [`MsaaRetrofit::new`] under a memory budget: the twins' bytes
    /// (formats × size × samples) are estimated before they are allocated
    /// and, over `budget`, the sample count steps down to the highest count
    /// the driver offers that fits, with a `log::warn!` line kept in
    /// [`MsaaRetrofit::warnings`]; with a strict budget, or when no
    /// multisampled count fits (the retrofit cannot render single-sample
    /// for the host), it refuses with [`Error::MemoryBudget`]. The budget
    /// holds for [`MsaaRetrofit::set_samples`] and
    /// [`MsaaRetrofit::refresh`] too.
    pub fn with_budget(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
        budget: &MemoryBudget,
    ) -> Result<Self> {
        let (samples, warning) = Self::budgeted(gl, host_fbo, options.samples, budget)?;
        let mut retrofit = Self::new(
            gl,
            host_fbo,
            &RetrofitOptions {
                samples,
                ..options.clone()
            },
        )?;
        retrofit.options.samples = options.samples;
        retrofit.budget = Some(*budget);
        retrofit.warnings = warning.into_iter().collect();
        Ok(retrofit)
    }

    /// The sample count `budget` allows for twins of `host_fbo`'s attachments.
    fn budgeted(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        requested: u32,
        budget: &MemoryBudget,
    ) -> Result<(u32, Option<String>)> {
        let host = introspect(gl, host_fbo)?;
        let mut formats: Vec<Format> = host.colors.iter().map(|a| a.format).collect();
        formats.push(host.depth.format);
        let (w, h) = host.size();
        budget_twins(gl, &formats, w, h, requested, budget)
    }

    /// What the memory budget did, one line each (empty without one, or
    /// when the requested count fit).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Introspect `host_fbo` and build its multisampled twin.
    pub fn new(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Self> {
        let resolver = Resolver::new(gl)?;
        match Self::build(gl, host_fbo, options) {
            Ok((host, twin, target, rules, key)) => Ok(MsaaRetrofit {
                host,
                options: options.clone(),
                twin,
                target,
                rules,
                key,
                resolver,
                budget: None,
                warnings: Vec::new(),
            }),
            Err(e) => {
                resolver.destroy(gl);
                Err(e)
            }
        }
    }

    #[allow(clippy::type_complexity)]
    fn build(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<(
        HostFramebuffer,
        MultisampleTwin,
        Framebuffer,
        Vec<ResolveRule>,
        KeySource,
    )> {
        let host = introspect(gl, host_fbo)?;
        let mut rules = Vec::with_capacity(host.colors.len());
        for a in &host.colors {
            let Attachment::Color(i) = a.point else {
                continue;
            };
            let rule = options
                .rules
                .iter()
                .find(|(n, _)| *n == i)
                .map_or(a.format.default_rule(), |(_, r)| *r);
            if a.format.default_rule() == ResolveRule::Select && rule != ResolveRule::Select {
                return Err(Error::UnsupportedFormat {
                    attachment: a.point.name(),
                    format: a.format.name().into(),
                    reason: format!(
                        "integer values can only be selected, not resolved by `{rule}`"
                    ),
                });
            }
            rules.push(rule);
        }
        for (n, _) in &options.rules {
            if !host.colors.iter().any(|a| a.point == Attachment::Color(*n)) {
                return Err(Error::Retrofit {
                    attachment: Attachment::Color(*n).name(),
                    reason:
                        "a rule is given for it but the host framebuffer has nothing attached there"
                            .into(),
                });
            }
        }
        let key = match options.position_attachment {
            None => KeySource::Depth,
            Some(n) => {
                let k = host
                    .colors
                    .iter()
                    .position(|a| a.point == Attachment::Color(n))
                    .ok_or_else(|| Error::Retrofit {
                        attachment: Attachment::Color(n).name(),
                        reason: "named as the position attachment but nothing is attached there"
                            .into(),
                    })?;
                if host.colors[k].format.default_rule() == ResolveRule::Select {
                    return Err(Error::UnsupportedFormat {
                        attachment: Attachment::Color(n).name(),
                        format: host.colors[k].format.name().into(),
                        reason: "the depth key needs a floating-point position".into(),
                    });
                }
                KeySource::Position(k)
            }
        };
        let mut specs: Vec<TwinSpec> = host
            .colors
            .iter()
            .map(|a| TwinSpec {
                point: a.point,
                format: a.format,
                name: a.point.name(),
            })
            .collect();
        specs.push(TwinSpec {
            point: host.depth.point,
            format: host.depth.format,
            name: host.depth.point.name(),
        });
        let (w, h) = host.size();
        let twin = MultisampleTwin::new(gl, &specs, &host.draw_buffers, w, h, options.samples)?;
        // The resolve writes output k into the host's k-th colour texture.
        let mut attachments: Vec<(Attachment, TextureRef)> = host
            .colors
            .iter()
            .enumerate()
            .map(|(k, a)| (Attachment::Color(k as u32), a.texture_ref()))
            .collect();
        attachments.push((host.depth.point, host.depth.texture_ref()));
        let draw: Vec<Option<u32>> = (0..host.colors.len() as u32).map(Some).collect();
        let target =
            match Framebuffer::new(gl, "resolve target (host textures)", &attachments, &draw) {
                Ok(f) => f,
                Err(e) => {
                    twin.destroy(gl);
                    return Err(e);
                }
            };
        Ok((host, twin, target, rules, key))
    }

    /// The multisampled framebuffer: bind it instead of the host's for the geometry pass.
    pub fn framebuffer(&self) -> glow::Framebuffer {
        self.twin.fbo.raw
    }

    /// The real sample count.
    pub fn samples(&self) -> u32 {
        self.twin.samples
    }

    /// What was found in the host's framebuffer.
    pub fn host(&self) -> &HostFramebuffer {
        &self.host
    }

    /// The multisampled twins (for techniques that read samples directly).
    pub fn twin(&self) -> &MultisampleTwin {
        &self.twin
    }

    /// The resolve rule of each host colour attachment, in attachment order.
    pub fn rules(&self) -> &[ResolveRule] {
        &self.rules
    }

    /// Where the depth key comes from (an index into the host's colour attachments).
    pub fn key(&self) -> KeySource {
        self.key
    }

    /// The resolve's inputs: the twins in host colour order, and depth.
    pub fn inputs(&self) -> Result<(TextureRef, Vec<TextureRef>)> {
        let depth = self
            .twin
            .depth()
            .map(TextureRef::from)
            .ok_or_else(|| Error::Retrofit {
                attachment: self.host.depth.point.name(),
                reason: "its multisampled twin is missing".into(),
            })?;
        let colors = self
            .host
            .colors
            .iter()
            .filter_map(|a| self.twin.texture(a.point).map(TextureRef::from))
            .collect();
        Ok((depth, colors))
    }

    /// Resolve the twins into the host's textures.
    pub fn resolve(&mut self, gl: &glow::Context, params: &ResolveParams) -> Result<()> {
        let (depth, colors) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
        };
        self.resolver.run(gl, &inputs, &self.target, params, false)
    }

    /// How the resolve finds its one-sample pixels (uniform pixels,
    /// pixels outside a selective-AA selection). The results are identical;
    /// which is fastest depends on the GPU ([`Schedule`] says why).
    pub fn set_schedule(&mut self, schedule: Schedule) -> Result<()> {
        self.resolver.set_schedule(schedule)
    }

    /// The resolve's schedule.
    pub fn schedule(&self) -> Schedule {
        self.resolver.schedule()
    }

    /// Resolve into another target (its colour `k` receives host attachment
    /// `k`; with `complex_output`, draw buffer `colors.len()` gets the
    /// complex-pixel mask).
    pub fn resolve_into(
        &mut self,
        gl: &glow::Context,
        target: &Framebuffer,
        params: &ResolveParams,
        complex_output: bool,
    ) -> Result<()> {
        let (depth, colors) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
        };
        self.resolver
            .run(gl, &inputs, target, params, complex_output)
    }

    /// Re-read the host framebuffer (after the host resized or re-allocated
    /// its textures) and rebuild the twins. The old twins are freed only once
    /// the new ones exist, so a failure leaves the retrofit working as before.
    pub fn refresh(&mut self, gl: &glow::Context) -> Result<()> {
        let options = self.options.clone();
        self.rebuild(gl, &options)
    }

    /// Change the sample count at run time.
    pub fn set_samples(&mut self, gl: &glow::Context, samples: u32) -> Result<()> {
        let mut options = self.options.clone();
        options.samples = samples;
        self.rebuild(gl, &options)
    }

    fn rebuild(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let (mut budgeted, mut warnings) = (options.clone(), Vec::new());
        if let Some(budget) = &self.budget {
            let (samples, warning) = Self::budgeted(gl, self.host.fbo, options.samples, budget)?;
            budgeted.samples = samples;
            warnings.extend(warning);
        }
        let (host, twin, target, rules, key) = Self::build(gl, self.host.fbo, &budgeted)?;
        self.warnings = warnings;
        let old_twin = std::mem::replace(&mut self.twin, twin);
        let old_target = std::mem::replace(&mut self.target, target);
        old_twin.destroy(gl);
        old_target.destroy(gl);
        self.host = host;
        self.rules = rules;
        self.key = key;
        self.options = options.clone();
        Ok(())
    }

    /// Free everything this crate created (never the host's objects).
    pub fn destroy(self, gl: &glow::Context) {
        self.twin.destroy(gl);
        self.target.destroy(gl);
        self.resolver.destroy(gl);
    }
}
