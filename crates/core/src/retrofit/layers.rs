//! The retrofit around the host's own draws after the resolve: the second
//! layer's copies and mix around the host's second lighting, and the
//! multisampled forward target for what the host draws after lighting.

use super::MsaaRetrofit;
use super::checks::{
    bind_output_where, bound_to, check_output, clear_host_errors, deleted_by_host, settle,
};
use crate::forward::ForwardTarget;
use crate::gl::{SetupState, TextureRef, destroy_object};
use crate::second_layer::SecondLayer;
use crate::{Error, Result};
use glow::HasContext;

impl MsaaRetrofit {
    /// With two layers ([`ResolveSettings::layers`](crate::resolve::ResolveSettings::layers) = 2), after the host lit
    /// the first layer into `output` (its framebuffer; `None` for the
    /// default framebuffer; the lit colour is its first draw buffer's, the
    /// G-buffer's size): keep that lit image, and put the second layer into
    /// the host's G-buffer textures and depth (the stencil stays the first
    /// layer's). The host then runs its lighting again, unchanged, and calls
    /// [`MsaaRetrofit::finish_second_layer`]. `false`, and nothing done, with
    /// one layer.
    ///
    /// Where a pixel has no second cluster the second layer holds the clear
    /// depth (and colours nothing reads), so a lighting pass that skips
    /// background (by a depth test or its own test of the depth value)
    /// skips it; its output there is not used.
    pub fn begin_second_layer(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<bool> {
        Ok(self.begin_second(gl, output, false)?.is_some())
    }

    /// [`MsaaRetrofit::begin_second_layer`], for a host that lights the
    /// second layer into the crate's own target instead of `output`: the
    /// framebuffer returned, of `output`'s format and the G-buffer's size,
    /// holding what `output` would hold for a second lighting into it:
    ///
    /// - colour: [`RetrofitOptions::lit_clear`](crate::RetrofitOptions::lit_clear)
    ///   where the host declared it (the colour its lit target shows where
    ///   its lighting writes nothing), else a copy of `output`'s lit first
    ///   layer (a pixel the second lighting leaves unwritten mixes to the
    ///   first layer's value); never the host's last `glClearColor`;
    /// - depth: where `output`'s depth attachment is the G-buffer's depth
    ///   image (a lighting that depth-tests against the G-buffer's depth: a
    ///   compose pass at z = 1 with `GL_GREATER`, a background pass with
    ///   `GL_LEQUAL`), the second layer's depth, as the G-buffer holds it
    ///   during the second lighting (in a 24-bit depth); else the host's
    ///   clear depth (`glClearDepth`), as a lit target cleared before its
    ///   lighting holds;
    /// - stencil: [`SECOND_LAYER_SELECTED`](crate::second_layer::SECOND_LAYER_SELECTED)
    ///   exactly where a pixel has a second layer (every pixel, where no
    ///   selection could be made).
    ///
    /// The host binds it in place of `output`
    /// for its second lighting, changing nothing else; with
    /// `glStencilFunc(GL_EQUAL, SECOND_LAYER_SELECTED, 0xFF)` and stencil
    /// writes off it lights only the pixels the mix reads. It must not
    /// clear the stencil. This is the route for a host lighting into the
    /// default framebuffer, to which no stencil texture attaches; and its
    /// depth test cannot reject the second lighting as the first lighting's
    /// depth in `output` would. `None`, and nothing done, with one layer.
    /// [`MsaaRetrofit::finish_second_layer`] takes the same `output`.
    pub fn begin_second_layer_own_target(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<Option<glow::Framebuffer>> {
        Ok(self.begin_second(gl, output, true)?.flatten())
    }

    /// Both begins: `Some` when the host is to light again, holding the
    /// crate's own target with `own_target`.
    fn begin_second(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        own_target: bool,
    ) -> Result<Option<Option<glow::Framebuffer>>> {
        let Some(second) = &mut self.second else {
            return Ok(None);
        };
        second.end_first_lighting(gl);
        if self.forward.as_ref().is_some_and(|f| f.drawing) {
            return Err(Error::invalid(
                "begin_second_layer between begin_forward and finish_forward: light both layers before the forward pass",
            ));
        }
        clear_host_errors(gl);
        crate::host::check_unchanged(gl, &self.host)?;
        if let Some(what) = second.own_target_deleted(gl) {
            return Err(deleted_by_host("the second lighting's own target", what));
        }
        check_output(gl, output)?;
        let host = SetupState::capture(gl).guard(gl);
        let profile = &mut self.profile;
        let mut result = second.begin(
            gl,
            output,
            self.options.restore_first_layer,
            own_target.then_some(self.options.lit_clear),
            profile,
        );
        // The host's stencil, for its lighting's tests: the second
        // cluster's seed sample's (the first layer's comes back in finish).
        if let (Ok(_), Some(s), Some(depth), Some(reference)) = (
            &result,
            &self.stencil,
            self.twin.depth(),
            second.reference(),
        ) {
            if let Err(e) = profile.time(gl, "second layer: seed stencil", || {
                s.pass
                    .run(gl, depth, &self.twin.fbo, Some(reference), &s.target)
            }) {
                result = Err(e);
            }
        }
        drop(host);
        match result {
            Ok(own) => {
                // Counted from here to finish: the host's second lighting.
                second.lighting_begins(gl);
                settle(gl, "beginning the second layer", Ok(Some(own)))
            }
            Err(e) => {
                second.abandon_check(gl);
                settle(gl, "beginning the second layer", Err(e))
            }
        }
    }

    /// After the host lit the second layer into `output` (the one given to
    /// [`MsaaRetrofit::begin_second_layer`]): write
    /// `mix(first, second, α)` into it ([`RetrofitOptions::layer_mix`](crate::RetrofitOptions::layer_mix); the
    /// first layer exactly where `α` is 0) and put the first layer back into
    /// the host's G-buffer textures and depth (as much of it as
    /// [`RetrofitOptions::restore_first_layer`](crate::RetrofitOptions::restore_first_layer) said at `begin`). The
    /// host's GL state is as it was, but for one binding: where the host
    /// left [`MsaaRetrofit::begin_second_layer_own_target`]'s framebuffer
    /// bound (for drawing, reading or both), `output` is bound there
    /// instead, as if the host had lit into it, so that a read-back or a
    /// pass that follows reads the mixed image.
    pub fn finish_second_layer(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<()> {
        let Some(second) = &mut self.second else {
            return Err(Error::invalid(
                "finish_second_layer needs two layers (ResolveSettings::layers = 2)",
            ));
        };
        clear_host_errors(gl);
        if let Err(e) = crate::host::check_unchanged(gl, &self.host) {
            // The first layer has no images left to go back into: the
            // frame is over, and `refresh` reads the new G-buffer.
            second.lighting = false;
            return Err(e);
        }
        if let Some(what) = second.own_target_deleted(gl) {
            second.lighting = false;
            second.abandon_check(gl);
            return Err(deleted_by_host("the second lighting's own target", what));
        }
        // Where the host left the own target bound, its output is bound
        // after the finish, as if it had lit into it.
        let bound = second
            .own_target_framebuffer()
            .map_or((false, false), |own| bound_to(gl, own));
        let mut host = SetupState::capture(gl);
        // The mix tests the selection's stencil.
        host.keep_stencil_func(gl)?;
        let host = host.guard(gl);
        let result = second.finish(gl, output, &mut self.profile);
        drop(host);
        bind_output_where(gl, bound, output);
        settle(gl, "finishing the second layer", result)
    }

    /// MSAA for what the host draws forward after lighting (light cubes,
    /// transparent objects, particles): after the lighting (and, with two
    /// layers, after [`MsaaRetrofit::finish_second_layer`]), copy the lit
    /// image of `output` (the host's framebuffer, its first draw buffer's
    /// image; `None` for the default framebuffer) into every sample of a
    /// multisampled colour target, attached with the G-buffer twins'
    /// multisampled depth (and stencil) as the geometry pass left them, and
    /// return that framebuffer. The host binds it in place of `output`,
    /// draws its forward objects unchanged (its own depth test, blending
    /// and stencil state; the depth is its own depth convention, as drawn),
    /// and calls [`MsaaRetrofit::finish_forward`]. The target is made on
    /// the first call for an output and kept; a host that writes `output`
    /// through `GL_FRAMEBUFFER_SRGB` should leave it on as it lit.
    ///
    /// What the forward objects write into depth and stencil goes into the
    /// twins' depth, which the next geometry pass clears; `output`'s own
    /// depth is not changed.
    pub fn begin_forward(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<glow::Framebuffer> {
        if self.second.as_ref().is_some_and(|s| s.lighting) {
            return Err(Error::invalid(
                "begin_forward between begin_second_layer and finish_second_layer: finish the second layer first",
            ));
        }
        if self.forward.as_ref().is_some_and(|f| f.drawing) {
            return Err(Error::invalid(
                "begin_forward was called twice: call finish_forward after the forward objects",
            ));
        }
        if let Some(second) = &mut self.second {
            second.end_first_lighting(gl);
        }
        clear_host_errors(gl);
        if let Some(what) = self.forward.as_ref().and_then(|f| f.deleted(gl)) {
            return Err(deleted_by_host("the forward target", what));
        }
        let host = SetupState::capture(gl).guard(gl);
        let framebuffer_srgb = unsafe { gl.is_enabled(glow::FRAMEBUFFER_SRGB) };
        let result = self
            .forward_for(gl, output, framebuffer_srgb)
            .and_then(|()| {
                let forward = self
                    .forward
                    .as_mut()
                    .ok_or_else(|| Error::invalid("the forward target was not made"))?;
                self.profile.time(gl, "forward: fill", || forward.begin(gl))
            });
        drop(host);
        settle(gl, "beginning the forward target", result)
    }

    /// The forward target for `output`, made again when the output, the
    /// way the host writes it or the layer mix changed.
    fn forward_for(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        framebuffer_srgb: bool,
    ) -> Result<()> {
        if self
            .forward
            .as_ref()
            .is_some_and(|f| f.serves(output, framebuffer_srgb, &self.options.layer_mix))
        {
            return Ok(());
        }
        if let Some(old) = self.forward.take() {
            destroy_object(gl, old);
        }
        let lit =
            crate::lit_output::LitOutput::inspect(gl, output, framebuffer_srgb, self.host.size())?;
        self.forward = Some(ForwardTarget::new(
            gl,
            lit,
            &self.twin,
            &self.options.layer_mix,
        )?);
        Ok(())
    }

    /// After the host drew its forward objects into
    /// [`MsaaRetrofit::begin_forward`]'s framebuffer: average each pixel's
    /// samples into `output`'s lit image (in the domain of
    /// [`RetrofitOptions::layer_mix`](crate::RetrofitOptions::layer_mix)), leaving every pixel no forward
    /// object touched bit for bit as it was. The host's GL state is as it
    /// was, but for one binding: where the host left
    /// [`MsaaRetrofit::begin_forward`]'s framebuffer bound (for drawing,
    /// reading or both), `output` is bound there instead, as if the host
    /// had drawn into it, so that a read-back (`glReadBuffer(GL_BACK)`,
    /// `glReadPixels`) or a post pass that follows reads the finished
    /// image.
    pub fn finish_forward(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<()> {
        let Some(forward) = self.forward.as_mut().filter(|f| f.drawing) else {
            return Err(Error::invalid("finish_forward without begin_forward"));
        };
        if forward.output() != output {
            forward.drawing = false;
            return Err(Error::invalid(
                "finish_forward was given another output than begin_forward",
            ));
        }
        clear_host_errors(gl);
        if let Some(what) = forward.deleted(gl) {
            forward.drawing = false;
            return Err(deleted_by_host("the forward target", what));
        }
        // Where the host left the forward target bound, its output is
        // bound after the finish, as if it had drawn into it.
        let bound = bound_to(gl, forward.framebuffer());
        let host = SetupState::capture(gl).guard(gl);
        let result = self
            .profile
            .time(gl, "forward: resolve", || forward.finish(gl));
        drop(host);
        bind_output_where(gl, bound, output);
        settle(gl, "resolving the forward target", result)
    }

    /// The bytes the forward target allocates (0 before the first
    /// [`MsaaRetrofit::begin_forward`]).
    pub fn forward_bytes(&self) -> u64 {
        self.forward.as_ref().map_or(0, ForwardTarget::bytes)
    }

    /// The second layer's coverage `α = (n2 + j2) / N` per pixel (R16F, in
    /// red; 0 where a pixel has one cluster), as of the last resolve; `None`
    /// with one layer.
    pub fn second_layer_coverage(&self) -> Option<TextureRef> {
        self.second.as_ref().map(|s| TextureRef::from(s.coverage()))
    }

    /// The pixels of the last resolve that have a second cluster, as a
    /// stencil: a `DEPTH24_STENCIL8` texture whose stencil is
    /// [`SECOND_LAYER_SELECTED`](crate::second_layer::SECOND_LAYER_SELECTED)
    /// exactly where the coverage is above 0 and 0 elsewhere (its depth is
    /// not defined: test the stencil only, and do not write it). A host
    /// may attach it as the depth-stencil attachment of the framebuffer its
    /// second lighting draws into and light only those pixels
    /// (`glStencilFunc(GL_EQUAL, 1, 0xFF)`), instead of a mask of its own;
    /// the mix keeps the first layer's lit value everywhere else. `None`
    /// with one layer, or where the first resolve had no draw buffer left
    /// for the flag the selection is made from.
    pub fn second_layer_selection(&self) -> Option<TextureRef> {
        self.second
            .as_ref()
            .and_then(SecondLayer::selection)
            .map(TextureRef::from)
    }

    /// The second layer's G-buffer as of the last resolve: its colour
    /// textures in host colour order (the host's formats; meaningful where
    /// the coverage is above 0) and its depth-buffer values (R32F, the
    /// clear depth where the coverage is 0); `None` with one layer. For
    /// hosts that light it with a pass of their own.
    pub fn second_layer_gbuffer(&self) -> Option<(Vec<TextureRef>, TextureRef)> {
        self.second.as_ref().map(|s| {
            let (colors, depth) = s.gbuffer();
            (
                colors.iter().map(TextureRef::from).collect(),
                TextureRef::from(depth),
            )
        })
    }

    /// The bytes the second layer allocates (0 with one layer): its
    /// G-buffer, the first layer's copy kept during the second lighting,
    /// the coverage, and the two lit copies once an output was given.
    pub fn second_layer_bytes(&self) -> u64 {
        self.second.as_ref().map_or(0, SecondLayer::bytes)
    }
}
