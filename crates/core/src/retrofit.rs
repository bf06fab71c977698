//! The two-line integration: multisampled twins of a host engine's G-buffer,
//! resolved back into the host's own textures.
//!
//! ```text
//! geometry pass:  gl.bind_framebuffer(FRAMEBUFFER, Some(msaa.framebuffer()));   // instead of the host's
//! after it:       msaa.resolve(&gl, &params)?;                                    // writes the host's textures
//! ```
//! The host's model and lighting shaders do not change: the twins have the
//! same formats, attachment points and draw-buffer mapping as the host's FBO.

use crate::frame::Frame;
use crate::gbuffer::{MemoryBudget, MultisampleTwin, TwinSpec, budget_twins};
use crate::gl::{Attachment, ColorAttachment, Format, Framebuffer, TextureRef, check_error};
use crate::resolve::{
    KeySource, ResolveInputs, ResolveParams, ResolveRule, ResolveSettings, ResolveSlot, Resolver,
    Schedule,
};
use crate::{Error, Result};
use glow::HasContext;

/// How a host G-buffer is multisampled and resolved: everything that does
/// not change from frame to frame, given once. The programs it needs are
/// compiled when the retrofit is made; [`MsaaRetrofit::set_options`]
/// changes it and rebuilds what must be rebuilt.
#[derive(Clone, Debug, PartialEq)]
pub struct RetrofitOptions {
    /// Requested samples per pixel (the driver's real count is used:
    /// [`MsaaRetrofit::samples`]).
    pub samples: u32,
    /// Rules for colour attachments by attachment number; the others take
    /// their format's default ([`ResolveRule::default_for`]: blend, select for
    /// integers).
    pub rules: Vec<(ColorAttachment, ResolveRule)>,
    /// The colour attachment holding view-space position, whose `-z` is
    /// the depth key; `None` (the default) linearises the depth attachment
    /// with each frame's projection instead.
    pub position_attachment: Option<ColorAttachment>,
    /// Method, window, fast path and selective anti-aliasing.
    pub resolve: ResolveSettings,
    /// How one-sample pixels are found ([`Schedule`]).
    pub schedule: Schedule,
    /// A limit on the twins' memory: over it, the sample count steps down
    /// (with a line in [`MsaaRetrofit::warnings`]) or, strict, the retrofit
    /// refuses with [`Error::MemoryBudget`].
    pub memory_budget: Option<MemoryBudget>,
}

impl Default for RetrofitOptions {
    fn default() -> Self {
        RetrofitOptions {
            samples: 4,
            rules: Vec::new(),
            position_attachment: None,
            resolve: ResolveSettings::default(),
            schedule: Schedule::OnePass,
            memory_budget: None,
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
    /// What the budget did (a stepped-down sample count), one line each.
    warnings: Vec<String>,
}

/// What [`MsaaRetrofit::build`] makes from the host's framebuffer.
struct Built {
    host: HostFramebuffer,
    twin: MultisampleTwin,
    target: Framebuffer,
    rules: Vec<ResolveRule>,
    key: KeySource,
    warnings: Vec<String>,
}

impl Built {
    fn destroy(self, gl: &glow::Context) {
        self.twin.destroy(gl);
        self.target.destroy(gl);
    }
}

impl MsaaRetrofit {
    /// Introspect `host_fbo`, build its multisampled twins under
    /// `options` and compile the resolve's programs.
    ///
    /// Errors: [`Error::Retrofit`] or [`Error::UnsupportedFormat`] naming
    /// the attachment the host framebuffer cannot be retrofitted for,
    /// [`Error::MemoryBudget`] when a strict budget (or any budget, with no
    /// multisampled count that fits) refuses, and the GL layer's errors.
    pub fn new(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Self> {
        let mut resolver = Resolver::new(gl)?;
        if let Err(e) = resolver.set_schedule(options.schedule) {
            resolver.destroy(gl);
            return Err(e);
        }
        let built = match Self::build(gl, host_fbo, options) {
            Ok(b) => b,
            Err(e) => {
                resolver.destroy(gl);
                return Err(e);
            }
        };
        let mut retrofit = MsaaRetrofit {
            host: built.host,
            options: options.clone(),
            twin: built.twin,
            target: built.target,
            rules: built.rules,
            key: built.key,
            resolver,
            warnings: built.warnings,
        };
        if let Err(e) = retrofit.prepare(gl) {
            retrofit.destroy(gl);
            return Err(e);
        }
        Ok(retrofit)
    }

    /// The sample count `budget` allows for twins of `host`'s attachments.
    fn budgeted(
        gl: &glow::Context,
        host: &HostFramebuffer,
        requested: u32,
        budget: &MemoryBudget,
    ) -> Result<(u32, Option<String>)> {
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

    /// The options in force.
    pub fn options(&self) -> &RetrofitOptions {
        &self.options
    }

    fn build(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Built> {
        let host = introspect(gl, host_fbo)?;
        let mut rules = Vec::with_capacity(host.colors.len());
        for a in &host.colors {
            let Attachment::Color(i) = a.point else {
                continue;
            };
            let rule = options
                .rules
                .iter()
                .find(|(n, _)| *n == ColorAttachment(i))
                .map_or(ResolveRule::default_for(a.format), |(_, r)| *r);
            if ResolveRule::default_for(a.format) == ResolveRule::Select
                && rule != ResolveRule::Select
            {
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
            if !host.colors.iter().any(|a| a.point == Attachment::from(*n)) {
                return Err(Error::Retrofit {
                    attachment: n.name(),
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
                    .position(|a| a.point == Attachment::from(n))
                    .ok_or_else(|| Error::Retrofit {
                        attachment: n.name(),
                        reason: "named as the position attachment but nothing is attached there"
                            .into(),
                    })?;
                if ResolveRule::default_for(host.colors[k].format) == ResolveRule::Select {
                    return Err(Error::UnsupportedFormat {
                        attachment: n.name(),
                        format: host.colors[k].format.name().into(),
                        reason: "the depth key needs a floating-point position".into(),
                    });
                }
                KeySource::Position(ResolveSlot(k))
            }
        };
        let mut samples = options.samples;
        let mut warnings = Vec::new();
        if let Some(budget) = &options.memory_budget {
            let (fits, warning) = Self::budgeted(gl, &host, options.samples, budget)?;
            samples = fits;
            warnings.extend(warning);
        }
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
        let twin = MultisampleTwin::new(gl, &specs, &host.draw_buffers, w, h, samples)?;
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
        Ok(Built {
            host,
            twin,
            target,
            rules,
            key,
            warnings,
        })
    }

    /// Compile the programs the options' resolve uses.
    fn prepare(&mut self, gl: &glow::Context) -> Result<()> {
        let (depth, colors, points) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            attachments: &points,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
        };
        self.resolver
            .prepare(gl, &inputs, &self.target, &self.options.resolve, false)
    }

    /// The multisampled framebuffer: bind it instead of the host's for the geometry pass.
    pub fn framebuffer(&self) -> glow::Framebuffer {
        self.twin.fbo.raw()
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

    /// Where the depth key comes from (a slot among the host's colour
    /// attachments, in attachment order).
    pub fn key(&self) -> KeySource {
        self.key
    }

    /// The resolve's inputs: depth, and the twins in host colour order with
    /// the attachment each stands for.
    pub fn inputs(&self) -> Result<(TextureRef, Vec<TextureRef>, Vec<ColorAttachment>)> {
        let depth = self
            .twin
            .depth()
            .map(TextureRef::from)
            .ok_or_else(|| Error::Retrofit {
                attachment: self.host.depth.point.name(),
                reason: "its multisampled twin is missing".into(),
            })?;
        let mut colors = Vec::with_capacity(self.host.colors.len());
        let mut points = Vec::with_capacity(self.host.colors.len());
        for a in &self.host.colors {
            let (Some(twin), Attachment::Color(n)) = (self.twin.texture(a.point), a.point) else {
                return Err(Error::Retrofit {
                    attachment: a.point.name(),
                    reason: "its multisampled twin is missing".into(),
                });
            };
            colors.push(TextureRef::from(twin));
            points.push(ColorAttachment(n));
        }
        Ok((depth, colors, points))
    }

    /// The low-level parameters of a resolve of this frame.
    fn params(&self, frame: &Frame) -> Result<ResolveParams> {
        let (projection, fov_y) = frame.depth_terms()?;
        Ok(ResolveParams {
            settings: self.options.resolve,
            projection,
            fov_y,
            height_px: self.host.size().1,
        })
    }

    /// Resolve the twins into the host's textures: call it after the
    /// geometry pass, before the host's lighting reads its G-buffer.
    pub fn resolve(&mut self, gl: &glow::Context, frame: &Frame) -> Result<()> {
        let params = self.params(frame)?;
        let (depth, colors, points) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            attachments: &points,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
        };
        self.resolver.run(gl, &inputs, &self.target, &params, false)
    }

    /// Resolve into another target (its colour `k` receives host attachment
    /// `k`; with `complex_output`, draw buffer `colors.len()` gets the
    /// complex-pixel mask): for tools that inspect the resolve. Its
    /// programs are compiled on first use.
    pub fn resolve_into(
        &mut self,
        gl: &glow::Context,
        target: &Framebuffer,
        frame: &Frame,
        complex_output: bool,
    ) -> Result<()> {
        let params = self.params(frame)?;
        let (depth, colors, points) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            attachments: &points,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
        };
        self.resolver
            .run(gl, &inputs, target, &params, complex_output)
    }

    /// Change the options. Only what they change is rebuilt: the twins
    /// when the sample count, budget, rules or key change; the programs
    /// whenever the resolve's permutation changes. On error the retrofit
    /// keeps working with the options it had.
    pub fn set_options(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let twins_change = options.samples != self.options.samples
            || options.memory_budget != self.options.memory_budget
            || options.rules != self.options.rules
            || options.position_attachment != self.options.position_attachment;
        if twins_change {
            return self.rebuild(gl, options);
        }
        let previous = self.options.clone();
        let previous_schedule = self.resolver.schedule();
        self.resolver.set_schedule(options.schedule)?;
        self.options = options.clone();
        if let Err(e) = self.prepare(gl) {
            self.options = previous;
            self.resolver.set_schedule(previous_schedule)?;
            return Err(e);
        }
        Ok(())
    }

    /// Re-read the host framebuffer (after the host resized or re-allocated
    /// its textures) and rebuild the twins. The old twins are freed only once
    /// the new ones exist, so a failure leaves the retrofit working as before.
    pub fn refresh(&mut self, gl: &glow::Context) -> Result<()> {
        let options = self.options.clone();
        self.rebuild(gl, &options)
    }

    /// Change the sample count: [`MsaaRetrofit::set_options`] with only
    /// `samples` changed.
    pub fn set_samples(&mut self, gl: &glow::Context, samples: u32) -> Result<()> {
        let options = RetrofitOptions {
            samples,
            ..self.options.clone()
        };
        self.rebuild(gl, &options)
    }

    fn rebuild(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let built = Self::build(gl, self.host.fbo, options)?;
        let previous_schedule = self.resolver.schedule();
        if let Err(e) = self.resolver.set_schedule(options.schedule) {
            built.destroy(gl);
            return Err(e);
        }
        let old = Built {
            host: std::mem::replace(&mut self.host, built.host),
            twin: std::mem::replace(&mut self.twin, built.twin),
            target: std::mem::replace(&mut self.target, built.target),
            rules: std::mem::replace(&mut self.rules, built.rules),
            key: std::mem::replace(&mut self.key, built.key),
            warnings: std::mem::replace(&mut self.warnings, built.warnings),
        };
        let old_options = std::mem::replace(&mut self.options, options.clone());
        match self.prepare(gl) {
            Ok(()) => {
                old.destroy(gl);
                Ok(())
            }
            Err(e) => {
                // Put the working twins back.
                let new = Built {
                    host: std::mem::replace(&mut self.host, old.host),
                    twin: std::mem::replace(&mut self.twin, old.twin),
                    target: std::mem::replace(&mut self.target, old.target),
                    rules: std::mem::replace(&mut self.rules, old.rules),
                    key: std::mem::replace(&mut self.key, old.key),
                    warnings: std::mem::replace(&mut self.warnings, old.warnings),
                };
                new.destroy(gl);
                self.options = old_options;
                self.resolver.set_schedule(previous_schedule)?;
                Err(e)
            }
        }
    }

    /// Free everything this crate created (never the host's objects).
    pub fn destroy(self, gl: &glow::Context) {
        self.twin.destroy(gl);
        self.target.destroy(gl);
        self.resolver.destroy(gl);
    }
}
