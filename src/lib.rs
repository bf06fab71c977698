//! # deferred-msaa
//!
//! Depth-aware multi-sample anti-aliasing for OpenGL 3.2+ deferred renderers,
//! added to an existing engine in two lines: bind the crate's multisampled
//! twin of the engine's G-buffer for the geometry pass, then call `resolve`,
//! which writes the engine's **own** G-buffer textures. The engine's model
//! and lighting shaders do not change.
//!
//! ```
//! # use deferred_msaa::context::{Backend, HeadlessContext};
//! # use deferred_msaa::gl::{Attachment, Format, Framebuffer, Texture2d, TextureRef};
//! use deferred_msaa::resolve::{DepthProjection, ResolveParams, ResolveSettings};
//! use deferred_msaa::retrofit::{MsaaRetrofit, RetrofitOptions};
//! use glow::HasContext;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # // A headless context; where this machine has no EGL the example stops here.
//! # let Ok(context) = HeadlessContext::new(Backend::Egl) else { return Ok(()) };
//! # let gl = context.gl();
//! # let (width, height) = (64, 36);
//! # // The engine's G-buffer: one colour texture and a depth texture on its own FBO.
//! # let albedo = Texture2d::new(gl, "engine albedo", Format::Rgba16f, width, height)?;
//! # let depth = Texture2d::new(gl, "engine depth", Format::Depth24, width, height)?;
//! # let engine_fbo = Framebuffer::new(gl, "engine gbuffer",
//! #     &[(Attachment::Color(0), TextureRef::from(&albedo)), (Attachment::Depth, TextureRef::from(&depth))],
//! #     &[Some(0)])?;
//! # let engine_gbuffer: glow::Framebuffer = engine_fbo.raw;
//! # let camera = deferred_msaa::scene::Camera::look_at(glam::Vec3::Z, glam::Vec3::ZERO, 1.0, 0.1, Some(100.0));
//! # let fov_y = camera.fov_y as f64;
//! # let projection = camera.projection(width as f32 / height as f32).as_dmat4();
//! // Once: multisampled twins of every attachment of the engine's G-buffer FBO.
//! let mut msaa = MsaaRetrofit::new(gl, engine_gbuffer, &RetrofitOptions::default())?;
//!
//! // Every frame:
//! unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.framebuffer())) }; // 1. instead of the engine's FBO
//! // ... the engine's unchanged geometry pass (here just a clear) ...
//! # unsafe {
//! #     gl.viewport(0, 0, width as i32, height as i32);
//! #     gl.clear_color(0.25, 0.5, 0.75, 1.0);
//! #     gl.clear_depth_f64(1.0);
//! #     gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
//! # }
//! msaa.resolve(gl, &ResolveParams {                                              // 2. into the engine's textures
//!     settings: ResolveSettings::default(),               // median reference, smooth depth window
//!     projection: DepthProjection::from_matrix(&projection, false, 1.0),
//!     fov_y,
//!     height_px: height,
//! })?;
//! // ... the engine's unchanged lighting pass reads its own G-buffer ...
//! # let mut texel = [0.0f32; 4];
//! # unsafe {
//! #     gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(engine_gbuffer));
//! #     gl.read_buffer(glow::COLOR_ATTACHMENT0);
//! #     gl.read_pixels(3, 3, 1, 1, glow::RGBA, glow::FLOAT, glow::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut texel))));
//! #     gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
//! # }
//! # assert_eq!(texel, [0.25, 0.5, 0.75, 1.0], "the resolve wrote the engine's own texture");
//!
//! msaa.destroy(gl); // at shutdown: frees only what the crate created
//! # engine_fbo.destroy(gl);
//! # albedo.destroy(gl);
//! # depth.destroy(gl);
//! # Ok(())
//! # }
//! ```
//!
//! [`retrofit::MsaaRetrofit::new`] reads the engine's FBO (attachments,
//! formats, draw buffers) and makes `GL_TEXTURE_2D_MULTISAMPLE` twins with
//! the same layout; [`retrofit::RetrofitOptions`] sets the sample count, a
//! resolve rule per attachment (normals: [`resolve::ResolveRule::Select`], as
//! [`gbuffer::GBufferLayout::recommended`] explains, or `BlendNormal`)
//! and where the depth key comes from (a view-space position attachment, or
//! the depth buffer linearised with the projection, as here).
//! [`retrofit::MsaaRetrofit::resolve`] blends, per pixel, only the samples
//! close in depth to a reference sample (`front`, `median`, `back`), so edge
//! pixels are never lit at a place where no surface is.
//!
//! # Where to go next
//!
//! - `examples/retrofit.rs`: a complete small engine, written with raw GL and
//!   no knowledge of this crate, and the four marked lines that add MSAA to it.
//! - `examples/headless.rs`: a glTF file to an anti-aliased PNG with the
//!   built-in [`renderer::Renderer`].
//! - `examples/viewer.rs`: a window with live switching of method, sample
//!   count, FXAA and the G-buffer view.
//! - [`context`]: headless EGL and OSMesa contexts; [`scene`]: glTF loading
//!   and built-in scenes; [`resolve`]: the resolve and its CPU reference;
//!   [`compare`]: FLIP, PSNR and the halo count.
#![warn(missing_docs)]

pub mod bench;
pub mod cli;
pub mod compare;
pub mod context;
pub mod dump;
pub mod error;
pub mod gbuffer;
pub mod gl;
pub mod plan;
pub mod readback;
pub mod renderer;
pub mod resolve;
pub mod retrofit;
pub mod scene;

pub use error::{Error, Result};
