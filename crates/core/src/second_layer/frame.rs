//! The second layer's steps in a frame: the selection, the copies of the
//! host's images around its second lighting, the occlusion check, and the
//! mix of the two lit layers into the host's output.

use super::passes::{CopyImage, OutputTarget, Set};
use super::{FirstLayerRestore, SELECTED, SecondLayer};
use crate::gl::{
    Attachment, Framebuffer, Made, Texture2d, TextureRef, check_error, destroy_object,
};
use crate::layer_mix::{MixKind, set_srgb};
use crate::lit_output::{LitOutput, bind_for_reading};
use crate::profile::StepProfile;
use crate::{Error, Result};
use glow::HasContext;

impl SecondLayer {
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
        // Refused before anything is made: a mix that cannot be inferred.
        MixKind::of(&self.mix, &output)?;
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
        let shares_depth = host.is_some_and(|f| shares_depth(gl, f, self.host_depth));
        let depth_kept = match host {
            Some(f) if !shares_depth => output_depth_copy(gl, f, (w, h)),
            _ => Ok(None),
        };
        let depth_kept = match depth_kept {
            Ok(kept) => kept,
            Err(e) => {
                for f in [target, masked].into_iter().flatten() {
                    f.destroy(gl);
                }
                lit_first_fbo.destroy(gl);
                lit_second_fbo.destroy(gl);
                lit_first.destroy(gl);
                lit_second.destroy(gl);
                return Err(e);
            }
        };
        self.output = Some(OutputTarget {
            shares_depth,
            depth_kept,
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

    /// Whether the output has a depth of its own that is kept across the
    /// second lighting into it.
    fn keeps_output_depth(&self) -> bool {
        self.output.as_ref().is_some_and(|o| o.depth_kept.is_some())
    }

    /// Copy the output's own depth (and stencil) aside (`keep`), or back
    /// into the output; nothing where it has none of its own.
    fn keep_output_depth(&self, gl: &glow::Context, keep: bool) {
        let Some(o) = &self.output else {
            return;
        };
        let (Some((texture, copy)), Some(host)) = (&o.depth_kept, o.output.host) else {
            return;
        };
        let bits = if texture.format.has_stencil() {
            glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT
        } else {
            glow::DEPTH_BUFFER_BIT
        };
        let (from, to) = if keep {
            (host, copy.raw())
        } else {
            (copy.raw(), host)
        };
        let (w, h) = (self.width as i32, self.height as i32);
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(from));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(to));
            gl.blit_framebuffer(0, 0, w, h, 0, 0, w, h, bits, glow::NEAREST);
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

    /// The crate's own target for the second lighting, prepared (the
    /// caller keeps the host's state): the lit second layer's copy, which
    /// starts cleared to the declared `lit_clear`, or else as the lit first
    /// layer (so a pixel the second lighting does not write mixes to the
    /// first layer's value; never to a colour the host happened to clear
    /// last), with the selection stencil
    /// ([`SECOND_LAYER_SELECTED`] on every pixel where no selection was
    /// made) and a depth as the output's would be during a second
    /// lighting into it: the second layer's depth where the output shares
    /// the G-buffer's depth, else the host's clear depth
    /// (`glClearDepth`), as a lit target cleared before its lighting holds.
    fn prepare_own_target(
        &self,
        gl: &glow::Context,
        lit_clear: Option<[f32; 4]>,
    ) -> Option<glow::Framebuffer> {
        let o = self.output.as_ref()?;
        let (w, h) = (self.width as i32, self.height as i32);
        unsafe {
            let depth = gl.get_parameter_f32(glow::DEPTH_CLEAR_VALUE);
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            match lit_clear {
                Some(colour) => {
                    gl.bind_framebuffer(glow::FRAMEBUFFER, Some(o.lit_second_fbo.raw()));
                    // The colour as glClearColor takes it: encoded on
                    // the way in where the host's writes are.
                    set_srgb(gl, o.output.srgb_writes);
                    gl.clear_buffer_f32_slice(glow::COLOR, 0, &colour);
                    gl.disable(glow::FRAMEBUFFER_SRGB);
                }
                None => {
                    gl.disable(glow::FRAMEBUFFER_SRGB);
                    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(o.lit_first_fbo.raw()));
                    gl.read_buffer(glow::COLOR_ATTACHMENT0);
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(o.lit_second_fbo.raw()));
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
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(o.lit_second_fbo.raw()));
            gl.depth_mask(true);
            if !o.shares_depth {
                gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[depth]);
            }
            if !self.selected.get() {
                gl.stencil_mask(0xFF);
                gl.clear_buffer_i32_slice(glow::STENCIL, 0, &[i32::from(SELECTED)]);
            }
        }
        if o.shares_depth {
            self.write_layer_depth(gl, &o.lit_second_fbo);
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
        own_target: Option<Option<[f32; 4]>>,
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
        if own_target.is_none() && self.keeps_output_depth() {
            profile.time(gl, "second layer: keep output depth", || {
                self.keep_output_depth(gl, true)
            });
        }
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
        let own = match own_target {
            Some(lit_clear) => profile.time(gl, "second layer: own target", || {
                self.prepare_own_target(gl, lit_clear)
            }),
            None => None,
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
        let probed = if self.own_target && self.output.as_ref().is_some_and(|o| o.shares_depth) {
            self.probe_own_depth(gl)
        } else {
            Ok(())
        };
        let checked = checked.and(probed);
        profile.time(gl, "second layer: mix", || self.draw_mix(gl))?;
        if !self.own_target && self.keeps_output_depth() {
            profile.time(gl, "second layer: restore output depth", || {
                self.keep_output_depth(gl, false)
            });
        }
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

    /// The check that the own target's depth, the second layer's, is what
    /// the host's second lighting tested against: a count of the selected
    /// pixels where it no longer holds it (a lighting that cleared or wrote
    /// it, and so lit the second layer as background where it tests the
    /// depth). The last frame's count, if still pending, is read first
    /// (a frame old, it waits); this one's now if the GPU has it, or on the
    /// first check, else at the next finish. The caller keeps the host's
    /// state.
    fn probe_own_depth(&mut self, gl: &glow::Context) -> Result<()> {
        let last = self.settle_probe(gl, true);
        let (Some(probe), Some(o)) = (&self.depth_probe, &self.output) else {
            return last;
        };
        probe.begin(gl);
        // Another occlusion query of the host's is active: no count.
        if unsafe { gl.get_error() } != glow::NO_ERROR {
            return last;
        }
        unsafe {
            o.lit_second_fbo.bind(gl);
            crate::gl::SavedState::prepare_fullscreen_pass(gl);
            gl.color_mask(false, false, false, false);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::NOTEQUAL);
            gl.depth_mask(false);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::EQUAL, i32::from(SELECTED), 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
            gl.stencil_mask(0);
            self.write_depth.program().bind(gl);
            TextureRef::from(&self.depth).bind(gl, 0);
        }
        self.write_depth.draw(gl, &self.vao);
        unsafe { gl.color_mask(true, true, true, true) };
        probe.end(gl);
        self.probe_pending = true;
        let wait = !self.probe_waited;
        last.and(self.settle_probe(gl, wait))
    }

    /// Read a pending count of the depth probe when it is there, or when
    /// `wait`.
    fn settle_probe(&mut self, gl: &glow::Context, wait: bool) -> Result<()> {
        let Some(probe) = self.depth_probe.as_ref().filter(|_| self.probe_pending) else {
            return Ok(());
        };
        let available = wait
            || unsafe { gl.get_query_parameter_u32(probe.raw, glow::QUERY_RESULT_AVAILABLE) } != 0;
        if !available {
            return Ok(());
        }
        self.probe_pending = false;
        self.probe_waited = true;
        let changed = probe.result(gl);
        if changed > 0 {
            return Err(Error::SecondLighting(format!(
                "the host's second lighting changed the own target's depth at {changed} samples of pixels with a second layer: \
                 that depth is the second layer's, as the G-buffer's depth the output shares holds it, for a lighting that tests \
                 against it, and a lighting that cleared it (glClear with GL_DEPTH_BUFFER_BIT) or wrote it lit the second layer \
                 as background there. In begin_second_layer_own_target's framebuffer clear colour only (or nothing) and leave \
                 depth writes off, or light into the output with begin_second_layer"
            )));
        }
        Ok(())
    }

    /// The second layer's depth into the host's depth attachment (its
    /// stencil untouched).
    fn depth_into_host(&self, gl: &glow::Context) {
        if self.depth_bits == 0 {
            return;
        }
        self.write_layer_depth(gl, &self.host_target);
    }

    /// The second layer's depth into `target`'s depth (its stencil and
    /// colours untouched).
    fn write_layer_depth(&self, gl: &glow::Context, target: &Framebuffer) {
        unsafe {
            target.bind(gl);
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
        let pass = match (MixKind::of(&self.mix, &o.output)?, &self.mix_curve) {
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

/// Whether host framebuffer `output`'s depth attachment is `depth` (the
/// G-buffer's depth image). The caller keeps the host's state.
fn shares_depth(
    gl: &glow::Context,
    output: glow::Framebuffer,
    depth: crate::host::HostImageKind,
) -> bool {
    use crate::host::HostImageKind;
    let (kind, name) = match depth {
        HostImageKind::Texture2d(t) | HostImageKind::TextureLayer { texture: t, .. } => {
            (glow::TEXTURE, t.0.get())
        }
        HostImageKind::Renderbuffer(r) => (glow::RENDERBUFFER, r.0.get()),
    };
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(output));
        let p = |pname| {
            gl.get_framebuffer_attachment_parameter_i32(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                pname,
            ) as u32
        };
        let shared = p(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE) == kind
            && p(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME) == name;
        // Nothing attached: the name query is an error, not the host's.
        let _ = gl.get_error();
        shared
    }
}

/// A texture of host framebuffer `output`'s depth format and a framebuffer
/// of it, to keep the output's depth in (`None` where it has no depth
/// attachment). The caller keeps the host's state.
fn output_depth_copy(
    gl: &glow::Context,
    output: glow::Framebuffer,
    (w, h): (u32, u32),
) -> Result<Option<(Texture2d, Framebuffer)>> {
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(output)) };
    let Some(depth) = crate::host::introspect_point(gl, Attachment::Depth)? else {
        return Ok(None);
    };
    Made::build(gl, |made| {
        let texture = made.keep(Texture2d::new(
            gl,
            "second layer: the output's depth kept",
            depth.format,
            w,
            h,
        )?);
        let fbo = made.keep(Framebuffer::new(
            gl,
            "second layer: the output's depth kept",
            &[(
                Attachment::for_depth_format(depth.format),
                TextureRef::from(&texture),
            )],
            &[],
        )?);
        Ok(Some((texture, fbo)))
    })
}
