//! The retrofit for a Rust host on another glow version (or on no glow at
//! all): [`ForeignRetrofit`] is made from the host's GL loader and the
//! host's raw G-buffer framebuffer name, and takes and returns GL object
//! names as plain integers, so no glow type crosses between the host and
//! the crate.
//!
//! A host built on glow 0.17 (three-d, Fyrox and others pin a glow of their
//! own) cannot hand its `glow::Context` to [`MsaaRetrofit::new`]: two
//! versions of one crate are two sets of types. Here the crate builds its
//! own glow function table from the host's loader, the same
//! `FnMut(&str) -> *const c_void` that glow's `from_loader_function` takes.
//! That table is a set of function pointers, not a context: the GL context
//! stays the host's, made and made current by the host.
//!
//! ```no_run
//! use deferred_msaa::foreign::ForeignRetrofit;
//! use deferred_msaa::{Frame, RetrofitOptions};
//! use std::ffi::c_void;
//! use std::num::NonZeroU32;
//! # fn host(load: &dyn Fn(&str) -> *const c_void, gbuffer: NonZeroU32, projection: [f32; 16]) -> Result<(), deferred_msaa::Error> {
//! // Once, with the host's context current: `load` is what the host built
//! // its own glow from (eglGetProcAddress, glutin's get_proc_address, …),
//! // `gbuffer` its G-buffer framebuffer's name (`framebuffer.0` in glow).
//! // SAFETY: the loader returns the entry points of the context current
//! // on this thread.
//! let mut msaa = unsafe { ForeignRetrofit::new(load, gbuffer, &RetrofitOptions::default())? };
//!
//! // Every frame: bind what `begin_frame` gives (a `NonZeroU32`; in glow
//! // 0.17, `glow::NativeFramebuffer(fbo)`) for the geometry pass, whose
//! // own clear then clears it.
//! let fbo = msaa.begin_frame()?;
//! # let _ = fbo;
//! msaa.resolve(&Frame::from_matrix(projection))?; // into the host's own textures
//! // ... the host's lighting ...
//!
//! msaa.destroy(); // at shutdown, the host's context current
//! # Ok(())
//! # }
//! ```
//!
//! # The contract
//!
//! - **Context.** The loader is the host's context's (or one whose entry
//!   points are the same: `eglGetProcAddress` and `glXGetProcAddress` give
//!   one set for every context; on WGL they are per context). Every call that
//!   touches GL, [`ForeignRetrofit::new`] and [`ForeignRetrofit::destroy`]
//!   included, needs that context current on the calling thread; the ones
//!   that do not say so in their docs ([`ForeignRetrofit::framebuffer`],
//!   [`ForeignRetrofit::samples`], the getters).
//! - **Thread.** One thread: the one the context is current on. The
//!   crate's live-object counters ([`crate::gl::live_objects`]) are per
//!   thread.
//! - **State.** Each call leaves the host's GL state as it found it
//!   (bindings, capabilities, masks, viewport, the per-draw-buffer state),
//!   and leaves no GL error pending; an error the host's own calls left
//!   pending before [`ForeignRetrofit::resolve`] is returned, with nothing
//!   resolved.
//! - **Objects.** The names returned belong to the retrofit: the host binds
//!   them, never deletes them. They change when the twins are rebuilt
//!   ([`ForeignRetrofit::set_options`], [`ForeignRetrofit::refresh`]), so a
//!   host asks for them each frame (no GL call). The names the host gives
//!   (its G-buffer, its lit outputs) stay the host's.
//! - **End.** [`ForeignRetrofit::destroy`] frees every GL object the
//!   retrofit made, and the function table. Dropping it without `destroy`
//!   frees no GL object (a drop cannot know the context is current): they
//!   leak until the context goes.
//!
//! The C API (`deferred-msaa-capi`) is built on this type.

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::retrofit::{MsaaRetrofit, RetrofitOptions};
use std::ffi::c_void;
use std::num::NonZeroU32;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};

/// [`MsaaRetrofit`] with its own GL function table, loaded through the
/// host's loader, and raw GL names in and out: for a Rust host whose glow
/// is not the crate's (see the [module docs](self) for the contract).
///
/// Each per-frame method is [`MsaaRetrofit`]'s of the same name; a
/// framebuffer the host gives is `Option<NonZeroU32>` (`None`: the default
/// framebuffer, as glow's `None`), and one the retrofit gives is a
/// `NonZeroU32` (`glow::NativeFramebuffer` wraps one in every glow
/// version).
pub struct ForeignRetrofit {
    gl: glow::Context,
    retrofit: MsaaRetrofit,
}

/// A framebuffer name of the host's, as the crate's glow type.
fn framebuffer(name: Option<NonZeroU32>) -> Option<glow::Framebuffer> {
    name.map(glow::NativeFramebuffer)
}

/// The error for a GL function the loader has no entry point for.
fn missing(name: &str) -> Error {
    Error::Unsupported {
        feature: "the retrofit".into(),
        requires: format!("{name}, one of the GL functions it calls"),
        found: format!("a loader that returns null for {name}; nothing was made or changed"),
    }
}

impl ForeignRetrofit {
    /// Build the crate's GL function table from `loader` and retrofit the
    /// host's G-buffer framebuffer `host_fbo` under `options`
    /// ([`MsaaRetrofit::new`]).
    ///
    /// `loader` returns the address of the GL entry point it is given the
    /// name of (`"glBindFramebuffer"`), or null where there is none. Every
    /// function the crate calls is asked for first: a null one is an error
    /// before anything is made (glow would keep the null pointer and fail
    /// only when it is called, in the middle of a pass). It also stores the
    /// per-draw-buffer queries glow does not wrap
    /// ([`crate::gl::load_state_functions`]), for the whole process.
    ///
    /// Errors: [`Error::Unsupported`] naming a function the loader returns
    /// null for; then those of [`MsaaRetrofit::new`]. Whatever the result,
    /// the host's GL state is as it was and no GL error is left pending.
    ///
    /// # Safety
    ///
    /// The host's GL context is current on the calling thread, and
    /// `loader` returns entry points of that context (or null): the
    /// retrofit calls them, through this and every later method, as the
    /// functions their names say.
    pub unsafe fn new(
        mut loader: impl FnMut(&str) -> *const c_void,
        host_fbo: NonZeroU32,
        options: &RetrofitOptions,
    ) -> Result<Self> {
        if let Some(name) = crate::gl::first_missing_function(&mut loader) {
            return Err(missing(name));
        }
        // SAFETY: the caller's contract: entry points of the context
        // current on this thread, and none of the required ones null.
        let gl = unsafe { glow::Context::from_loader_function(&mut loader) };
        if let Some(name) = crate::gl::first_missing_conditional_function(&gl, &mut loader) {
            return Err(missing(name));
        }
        crate::gl::load_state_functions(&mut loader)?;
        let host = glow::NativeFramebuffer(host_fbo);
        // The core's guards put the host's state back while a panic
        // unwinds; a GL error left on the way is drained before it goes on.
        let retrofit =
            match catch_unwind(AssertUnwindSafe(|| MsaaRetrofit::new(&gl, host, options))) {
                Ok(result) => result?,
                Err(payload) => {
                    let _ = crate::gl::check_error(&gl, "a panic");
                    resume_unwind(payload)
                }
            };
        Ok(ForeignRetrofit { gl, retrofit })
    }

    /// The multisampled framebuffer to bind instead of the host's G-buffer
    /// for the geometry pass ([`MsaaRetrofit::framebuffer`]). No GL call:
    /// the context need not be current.
    pub fn framebuffer(&self) -> NonZeroU32 {
        self.retrofit.framebuffer().0
    }

    /// [`MsaaRetrofit::begin_frame`], required each frame before the
    /// geometry pass: check the twins still exist, clear them to
    /// [`RetrofitOptions::twin_clear`]'s values (or their depth to the
    /// sentinel the host's own clear replaces), and give
    /// [`ForeignRetrofit::framebuffer`].
    pub fn begin_frame(&mut self) -> Result<NonZeroU32> {
        Ok(self.retrofit.begin_frame(&self.gl)?.0)
    }

    /// The real sample count ([`MsaaRetrofit::samples`]). No GL call.
    pub fn samples(&self) -> u32 {
        self.retrofit.samples()
    }

    /// The options in force. No GL call.
    pub fn options(&self) -> &RetrofitOptions {
        self.retrofit.options()
    }

    /// What the memory budget did ([`MsaaRetrofit::warnings`]). No GL call.
    pub fn warnings(&self) -> &[String] {
        self.retrofit.warnings()
    }

    /// Resolve the twins into the host's own G-buffer textures, after the
    /// geometry pass and before the lighting ([`MsaaRetrofit::resolve`]).
    pub fn resolve(&mut self, frame: &Frame) -> Result<()> {
        self.retrofit.resolve(&self.gl, frame)
    }

    /// With two layers, after the host lit the first layer into `output`
    /// (`None`: the default framebuffer): `true` when the host is to light
    /// again into `output` and call
    /// [`ForeignRetrofit::finish_second_layer`]
    /// ([`MsaaRetrofit::begin_second_layer`]). `false` with one layer.
    pub fn begin_second_layer(&mut self, output: Option<NonZeroU32>) -> Result<bool> {
        self.retrofit
            .begin_second_layer(&self.gl, framebuffer(output))
    }

    /// [`ForeignRetrofit::begin_second_layer`] with the second lighting
    /// drawn into the crate's own target: the framebuffer to bind in place
    /// of `output` for it, or `None` with one layer
    /// ([`MsaaRetrofit::begin_second_layer_own_target`] says how it is
    /// cleared and what its stencil selects).
    pub fn begin_second_layer_own_target(
        &mut self,
        output: Option<NonZeroU32>,
    ) -> Result<Option<NonZeroU32>> {
        Ok(self
            .retrofit
            .begin_second_layer_own_target(&self.gl, framebuffer(output))?
            .map(|f| f.0))
    }

    /// After the second lighting: mix the two lit layers into `output` (the
    /// one given to begin) and put the first layer back into the host's
    /// G-buffer ([`MsaaRetrofit::finish_second_layer`]).
    pub fn finish_second_layer(&mut self, output: Option<NonZeroU32>) -> Result<()> {
        self.retrofit
            .finish_second_layer(&self.gl, framebuffer(output))
    }

    /// MSAA for what the host draws forward after lighting: the
    /// multisampled framebuffer to bind in place of `output` for it
    /// ([`MsaaRetrofit::begin_forward`]).
    pub fn begin_forward(&mut self, output: Option<NonZeroU32>) -> Result<NonZeroU32> {
        Ok(self
            .retrofit
            .begin_forward(&self.gl, framebuffer(output))?
            .0)
    }

    /// After the forward objects: average them into `output`'s lit image
    /// ([`MsaaRetrofit::finish_forward`]).
    pub fn finish_forward(&mut self, output: Option<NonZeroU32>) -> Result<()> {
        self.retrofit.finish_forward(&self.gl, framebuffer(output))
    }

    /// The `GL_TEXTURE_2D` (`DEPTH24_STENCIL8`) whose stencil selects the
    /// pixels with a second layer ([`MsaaRetrofit::second_layer_selection`]).
    /// No GL call.
    pub fn second_layer_selection(&self) -> Option<NonZeroU32> {
        self.retrofit.second_layer_selection().map(|t| t.raw.0)
    }

    /// The `GL_TEXTURE_2D` (R16F) of the second layer's coverage per pixel
    /// ([`MsaaRetrofit::second_layer_coverage`]). No GL call.
    pub fn second_layer_coverage(&self) -> Option<NonZeroU32> {
        self.retrofit.second_layer_coverage().map(|t| t.raw.0)
    }

    /// Change the options, rebuilding only what they change
    /// ([`MsaaRetrofit::set_options`]); ask for the framebuffer again.
    pub fn set_options(&mut self, options: &RetrofitOptions) -> Result<()> {
        self.retrofit.set_options(&self.gl, options)
    }

    /// Re-read the host's G-buffer after a resize and rebuild the twins
    /// ([`MsaaRetrofit::refresh`]); ask for the framebuffer again.
    pub fn refresh(&mut self) -> Result<()> {
        self.retrofit.refresh(&self.gl)
    }

    /// [`ForeignRetrofit::refresh`] for a host that made its G-buffer anew
    /// under another framebuffer name ([`MsaaRetrofit::refresh_with`]).
    pub fn refresh_with(&mut self, host_fbo: NonZeroU32) -> Result<()> {
        self.retrofit
            .refresh_with(&self.gl, glow::NativeFramebuffer(host_fbo))
    }

    /// The retrofit itself, for what this type does not forward (the
    /// profile, the twins' description). No GL call.
    pub fn retrofit(&self) -> &MsaaRetrofit {
        &self.retrofit
    }

    /// The crate's GL function table and the retrofit, for a caller that
    /// calls [`MsaaRetrofit`]'s methods itself (the C API does). The table
    /// is the crate's glow's, not the host's.
    pub fn parts_mut(&mut self) -> (&glow::Context, &mut MsaaRetrofit) {
        (&self.gl, &mut self.retrofit)
    }

    /// Free every GL object the retrofit made (never the host's), with the
    /// host's context current on the calling thread, and the function
    /// table. The host's state is kept, but for a binding of one of the
    /// freed objects (the retrofit's framebuffer left bound), which falls
    /// back to 0 as `glDelete*` makes it.
    pub fn destroy(self) {
        let ForeignRetrofit { gl, retrofit } = self;
        retrofit.destroy(&gl);
    }
}
