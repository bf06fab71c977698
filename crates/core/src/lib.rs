//! # deferred-msaa
//!
//! Depth-aware multi-sample anti-aliasing for OpenGL 3.2+ deferred renderers,
//! added to an existing engine in three calls a frame: `begin_frame`, which
//! gives the crate's multisampled twin of the engine's G-buffer to bind for
//! the geometry pass (its own clear and draws, unchanged), then `resolve`,
//! which writes the engine's **own** G-buffer textures. The engine's model
//! and lighting shaders do not change.
//!
//! A host learns three types: [`MsaaRetrofit`], [`RetrofitOptions`] (given
//! once) and [`Frame`] (each frame's projection).
//!
//! ```
//! use deferred_msaa::{Frame, MsaaRetrofit, RetrofitOptions};
//! use glow::HasContext;
//! # fn engine_gbuffer(gl: &glow::Context, w: i32, h: i32) -> (glow::Framebuffer, glow::Texture, glow::Texture) {
//! #     unsafe {
//! #         let tex = |internal: u32, format: u32, ty: u32| {
//! #             let t = gl.create_texture().unwrap();
//! #             gl.bind_texture(glow::TEXTURE_2D, Some(t));
//! #             gl.tex_image_2d(glow::TEXTURE_2D, 0, internal as i32, w, h, 0, format, ty, glow::PixelUnpackData::Slice(None));
//! #             t
//! #         };
//! #         let albedo = tex(glow::RGBA16F, glow::RGBA, glow::HALF_FLOAT);
//! #         let depth = tex(glow::DEPTH_COMPONENT24, glow::DEPTH_COMPONENT, glow::UNSIGNED_INT);
//! #         let fbo = gl.create_framebuffer().unwrap();
//! #         gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
//! #         gl.framebuffer_texture_2d(glow::FRAMEBUFFER, glow::COLOR_ATTACHMENT0, glow::TEXTURE_2D, Some(albedo), 0);
//! #         gl.framebuffer_texture_2d(glow::FRAMEBUFFER, glow::DEPTH_ATTACHMENT, glow::TEXTURE_2D, Some(depth), 0);
//! #         gl.bind_framebuffer(glow::FRAMEBUFFER, None);
//! #         (fbo, albedo, depth)
//! #     }
//! # }
//! # fn run(gl: &glow::Context) -> Result<(), deferred_msaa::Error> {
//! # let (width, height) = (64, 36);
//! # let (engine_fbo, albedo, depth) = engine_gbuffer(gl, width, height);
//! # let projection: [f32; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.002, -1.0, 0.0, 0.0, -0.2002, 0.0];
//! // Once: multisampled twins of every attachment of the engine's G-buffer
//! // FBO, and the resolve's programs, compiled now.
//! let mut msaa = MsaaRetrofit::new(gl, engine_fbo, &RetrofitOptions::default())?;
//!
//! // Every frame:
//! let fbo = msaa.begin_frame(gl)?; // 1. the way into a frame
//! unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) }; // 2. instead of the engine's FBO
//! // ... the engine's unchanged geometry pass: its clear, its draws (here just a clear) ...
//! # unsafe {
//! #     gl.viewport(0, 0, width, height);
//! #     gl.clear_color(0.25, 0.5, 0.75, 1.0);
//! #     gl.clear_depth_f64(1.0);
//! #     gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
//! # }
//! msaa.resolve(gl, &Frame::from_matrix(projection))?; // 3. into the engine's own textures
//! // ... the engine's unchanged lighting pass reads its own G-buffer ...
//! # let mut texel = [0u16; 4];
//! # unsafe {
//! #     gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(engine_fbo));
//! #     gl.read_buffer(glow::COLOR_ATTACHMENT0);
//! #     gl.read_pixels(3, 3, 1, 1, glow::RGBA, glow::HALF_FLOAT, glow::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut texel))));
//! #     gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
//! # }
//! # // 0.25, 0.5, 0.75 and 1.0 as half floats.
//! # assert_eq!(texel, [0x3400, 0x3800, 0x3A00, 0x3C00], "the resolve wrote the engine's own texture");
//!
//! msaa.destroy(gl); // at shutdown: frees only what the crate created
//! # unsafe {
//! #     gl.delete_framebuffer(engine_fbo);
//! #     gl.delete_texture(albedo);
//! #     gl.delete_texture(depth);
//! # }
//! # Ok(())
//! # }
//! # // The core makes no context: the doctest borrows the headless layer's,
//! # // and stops here on a machine without EGL.
//! # let Ok(context) = deferred_msaa_headless::HeadlessContext::new(deferred_msaa_headless::Backend::Egl) else { return };
//! # run(context.gl()).unwrap();
//! ```
//!
//! [`MsaaRetrofit::new`] reads the engine's FBO (attachments, formats, draw
//! buffers) and makes `GL_TEXTURE_2D_MULTISAMPLE` twins with the same
//! layout; [`RetrofitOptions`] sets the sample count, a resolve rule per
//! attachment ([`resolve::ResolveRule`]), where the depth key comes from (a
//! view-space position attachment, or the depth buffer linearised with the
//! frame's projection, as here) and the resolve's method and window.
//! [`MsaaRetrofit::resolve`] blends, per pixel, only the samples close in
//! depth to a reference sample (`front`, `median`, `back`), so edge pixels
//! are never lit at a place where no surface is.
//!
//! # Layers
//!
//! This crate is the core a host links: [`gl`] (owned GL objects, freed by
//! `destroy`, with live-object counters), [`gbuffer`] (layouts, twins, the
//! memory budget), [`resolve`] (the pass and its f64 CPU reference),
//! [`retrofit`] and [`readback`] (per-sample readback), and [`foreign`]
//! (the retrofit for a Rust host on another glow version: made from the
//! host's GL loader, raw GL names in and out). It depends on glow,
//! thiserror, log and bytemuck only; `glam` (a [`Frame`] from a `glam`
//! matrix) and `serde` are opt-in features. Headless contexts
//! (`deferred-msaa-headless`) and the demo renderer, scenes, bench and CLI
//! (`deferred-msaa-lab`) sit on top and are never needed by a host.
#![warn(missing_docs)]

mod clear_check;
pub mod error;
pub mod foreign;
pub mod forward;
pub mod frame;
pub mod gbuffer;
pub mod gl;
pub mod host;
mod layer_mix;
mod lighting_check;
mod lit_output;
pub mod profile;
pub mod readback;
pub mod resolve;
pub mod retrofit;
pub mod second_layer;

pub use error::{Error, Result};
pub use frame::{DepthMode, Frame, Projection};
pub use gl::ColorAttachment;
/// The GL bindings the crate is written against; hosts use the same version.
pub use glow;
pub use retrofit::{
    FirstLayerRestore, MsaaRetrofit, NormalAttachment, PositionSpace, RetrofitOptions, TwinClear,
};
pub use second_layer::LayerMix;
