//! A deferred renderer written the way a small Rust engine on glow 0.17
//! writes one, to try `deferred-msaa inject` on (docs/inject.md):
//!
//! - a surfaceless EGL context through `khronos-egl`, `libEGL.so.1` loaded at
//!   run time (as glutin loads it), GL entry points from `eglGetProcAddress`;
//!   no window and no swap;
//! - a one-call render: each call makes its G-buffer (one `RGBA16F`
//!   `GL_TEXTURE_2D_ARRAY`, layer 0 the albedo and a geometry mask, layer 1
//!   the normal, attached with `glFramebufferTextureLayer`, and a depth
//!   texture) and its lit target (`RGBA8`), draws, lights with the sRGB
//!   curve in the shader, reads the image back and deletes it all;
//! - the camera as one `viewProjection` uniform, made on the CPU (glam);
//! - thin bars against a bright sky, boxes on a floor.
//!
//! ```sh
//! cargo build --release --example inject_rust_engine
//! target/release/deferred-msaa inject --learn engine.toml -- \
//!     target/release/examples/inject_rust_engine out.rgba
//! ```
//!
//! Usage: `inject_rust_engine OUT.rgba [--frames N] [--reference DIR]
//! [--in-source]`. It renders N frames (3) and writes the last as raw RGBA8,
//! rows bottom-up. `--reference DIR` also writes the frame rendered at 4x
//! the width and height averaged 4x4 in linear light (`reference.rgba`) and
//! its edge pixels (`edges.mask`: 255 where the 16 depths under a pixel mix
//! sky and geometry or span more than 1% of the view distance).
//! `--in-source` adds the retrofit in the source, as `inject` applies it with
//! the profile in `tests/fast/inject/rust_engine.rs`: a
//! `deferred_msaa::foreign::ForeignRetrofit` made at the first call and
//! given each call's new G-buffer with `refresh_with`, two layers, the
//! lighting drawn again into the crate's own target. Without it, the
//! program makes no call into the crate. The tests run it under `inject`.

use std::error::Error;
use std::num::NonZeroU32;
use std::process::ExitCode;

use deferred_msaa::foreign::ForeignRetrofit;
use deferred_msaa::{ColorAttachment, Frame, LayerMix, NormalAttachment, RetrofitOptions};
use glam::{Mat4, Quat, Vec3};
use glow017::HasContext;
use khronos_egl as egl;

const WIDTH: i32 = 320;
const HEIGHT: i32 = 180;
const SUPERSAMPLE: i32 = 4;
const EGL_PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;

type Result<T> = std::result::Result<T, Box<dyn Error>>;

const GEOMETRY_VS: &str = r#"
layout (location = 0) in vec3 position;
layout (location = 1) in vec3 normal;
uniform mat4 viewProjection;
uniform mat4 model;
out vec3 worldNormal;
void main() {
    worldNormal = mat3(model) * normal;
    gl_Position = viewProjection * model * vec4(position, 1.0);
}
"#;

const GEOMETRY_FS: &str = r#"
in vec3 worldNormal;
uniform vec3 albedo;
layout (location = 0) out vec4 outAlbedo;
layout (location = 1) out vec4 outNormal;
void main() {
    outAlbedo = vec4(albedo, 1.0);
    outNormal = vec4(normalize(worldNormal), 1.0);
}
"#;

const LIGHTING_VS: &str = r#"
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const LIGHTING_FS: &str = r#"
uniform sampler2DArray gbuffer;
uniform vec3 sunDirection;
uniform vec2 viewport;
out vec4 color;
vec3 encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 albedo = texelFetch(gbuffer, ivec3(p, 0), 0);
    vec3 n = texelFetch(gbuffer, ivec3(p, 1), 0).xyz;
    float height = gl_FragCoord.y / viewport.y;
    vec3 sky = mix(vec3(0.55, 0.7, 0.95), vec3(0.85, 0.9, 1.0), height);
    float lit = 0.08 + 1.2 * max(dot(normalize(n + vec3(0.0, 0.0, 1e-6)), sunDirection), 0.0);
    vec3 c = albedo.a > 0.5 ? albedo.rgb * lit : sky;
    color = vec4(encode(c), 1.0);
}
"#;

/// One object of the scene: its model matrix and albedo.
struct Object {
    model: Mat4,
    albedo: Vec3,
}

fn scene() -> Vec<Object> {
    let object = |scale: Vec3, turn: f32, at: Vec3, albedo: Vec3| Object {
        model: Mat4::from_scale_rotation_translation(scale, Quat::from_rotation_y(turn), at),
        albedo,
    };
    let mut objects = vec![
        object(
            Vec3::new(4.0, 0.05, 4.0),
            0.0,
            Vec3::new(0.0, -0.55, 0.0),
            Vec3::new(0.5, 0.5, 0.45),
        ),
        object(
            Vec3::splat(0.5),
            0.5,
            Vec3::new(-1.2, 0.0, 0.3),
            Vec3::new(0.8, 0.3, 0.2),
        ),
        object(
            Vec3::splat(0.4),
            1.1,
            Vec3::new(1.1, -0.1, -0.4),
            Vec3::new(0.2, 0.5, 0.8),
        ),
    ];
    // Thin posts against the sky, one to three samples wide at 4x.
    for k in 0..6 {
        let x = -2.5 + 1.0 * k as f32;
        let thickness = 0.008 + 0.004 * k as f32;
        objects.push(object(
            Vec3::new(thickness, 1.6, thickness),
            0.3 * k as f32,
            Vec3::new(x, 1.0, -1.5),
            Vec3::new(0.9, 0.85, 0.7),
        ));
    }
    // A thin beam across them.
    objects.push(object(
        Vec3::new(3.2, 0.012, 0.012),
        0.05,
        Vec3::new(0.0, 2.3, -1.5),
        Vec3::new(0.3, 0.3, 0.35),
    ));
    objects
}

/// A unit cube's 36 vertices: position, normal.
fn cube() -> Vec<f32> {
    let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    let corners = [
        (-1.0, -1.0),
        (1.0, -1.0),
        (1.0, 1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
        (-1.0, -1.0),
    ];
    let mut v = Vec::with_capacity(36 * 6);
    for (n, u, w) in faces {
        for (a, b) in corners {
            for k in 0..3 {
                v.push(n[k] + a * u[k] + b * w[k]);
            }
            v.extend_from_slice(&n);
        }
    }
    v
}

/// The engine: its context's GL, its programs and its one mesh.
struct Engine {
    gl: glow017::Context,
    geometry: glow017::Program,
    lighting: glow017::Program,
    cube: glow017::VertexArray,
    cube_buffer: glow017::Buffer,
    empty: glow017::VertexArray,
    objects: Vec<Object>,
}

/// One rendered image: RGBA8 rows bottom-up, and the depth if asked.
struct Image {
    rgba: Vec<u8>,
    depth: Vec<f32>,
}

unsafe fn program(
    gl: &glow017::Context,
    version: &str,
    vs: &str,
    fs: &str,
) -> Result<glow017::Program> {
    unsafe {
        let program = gl.create_program()?;
        let mut shaders = Vec::new();
        for (kind, body) in [(glow017::VERTEX_SHADER, vs), (glow017::FRAGMENT_SHADER, fs)] {
            let shader = gl.create_shader(kind)?;
            gl.shader_source(shader, &format!("{version}{body}"));
            gl.compile_shader(shader);
            if !gl.get_shader_compile_status(shader) {
                return Err(gl.get_shader_info_log(shader).into());
            }
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        gl.link_program(program);
        if !gl.get_program_link_status(program) {
            return Err(gl.get_program_info_log(program).into());
        }
        for shader in shaders {
            gl.delete_shader(shader);
        }
        Ok(program)
    }
}

impl Engine {
    unsafe fn new(gl: glow017::Context) -> Result<Engine> {
        unsafe {
            let version = gl.version();
            let glsl = if (version.major, version.minor) >= (3, 3) {
                "#version 330 core\n"
            } else {
                "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n"
            };
            let geometry = program(&gl, glsl, GEOMETRY_VS, GEOMETRY_FS)?;
            let lighting = program(&gl, glsl, LIGHTING_VS, LIGHTING_FS)?;
            let cube_buffer = gl.create_buffer()?;
            let cube = gl.create_vertex_array()?;
            gl.bind_vertex_array(Some(cube));
            gl.bind_buffer(glow017::ARRAY_BUFFER, Some(cube_buffer));
            let vertices = self::cube();
            let bytes: Vec<u8> = vertices.iter().flat_map(|v| v.to_ne_bytes()).collect();
            gl.buffer_data_u8_slice(glow017::ARRAY_BUFFER, &bytes, glow017::STATIC_DRAW);
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow017::FLOAT, false, 24, 0);
            gl.enable_vertex_attrib_array(1);
            gl.vertex_attrib_pointer_f32(1, 3, glow017::FLOAT, false, 24, 12);
            gl.bind_vertex_array(None);
            let empty = gl.create_vertex_array()?;
            Ok(Engine {
                gl,
                geometry,
                lighting,
                cube,
                cube_buffer,
                empty,
                objects: scene(),
            })
        }
    }

    /// The camera's projection (GL's, depth to [-1, 1]) and view (looking
    /// down -z, y up) at `width` x `height`.
    fn camera(width: i32, height: i32) -> (Mat4, Mat4) {
        let (fov_y, near, far) = (0.75f32, 0.1f32, 50.0f32);
        let f = 1.0 / (fov_y / 2.0).tan();
        let aspect = width as f32 / height as f32;
        let projection = Mat4::from_cols_array(&[
            f / aspect,
            0.0,
            0.0,
            0.0,
            0.0,
            f,
            0.0,
            0.0,
            0.0,
            0.0,
            (far + near) / (near - far),
            -1.0,
            0.0,
            0.0,
            2.0 * far * near / (near - far),
            0.0,
        ]);
        let (eye, target) = (Vec3::new(0.3, 1.2, 5.5), Vec3::new(0.0, 0.9, 0.0));
        let forward = (target - eye).normalize();
        let side = forward.cross(Vec3::Y).normalize();
        let up = side.cross(forward);
        let view = Mat4::from_cols(
            side.extend(0.0),
            up.extend(0.0),
            (-forward).extend(0.0),
            eye.extend(1.0),
        )
        .inverse();
        (projection, view)
    }

    /// The one-call render: everything made, drawn, read back and deleted.
    unsafe fn render(
        &self,
        width: i32,
        height: i32,
        mut in_source: Option<&mut InSource>,
        want_depth: bool,
    ) -> Result<Image> {
        let gl = &self.gl;
        unsafe {
            // The G-buffer: one array texture's two layers and a depth texture.
            let layers = gl.create_texture()?;
            gl.bind_texture(glow017::TEXTURE_2D_ARRAY, Some(layers));
            gl.tex_image_3d(
                glow017::TEXTURE_2D_ARRAY,
                0,
                glow017::RGBA16F as i32,
                width,
                height,
                2,
                0,
                glow017::RGBA,
                glow017::HALF_FLOAT,
                glow017::PixelUnpackData::Slice(None),
            );
            for p in [glow017::TEXTURE_MIN_FILTER, glow017::TEXTURE_MAG_FILTER] {
                gl.tex_parameter_i32(glow017::TEXTURE_2D_ARRAY, p, glow017::NEAREST as i32);
            }
            let depth = gl.create_texture()?;
            gl.bind_texture(glow017::TEXTURE_2D, Some(depth));
            gl.tex_image_2d(
                glow017::TEXTURE_2D,
                0,
                glow017::DEPTH_COMPONENT24 as i32,
                width,
                height,
                0,
                glow017::DEPTH_COMPONENT,
                glow017::UNSIGNED_INT,
                glow017::PixelUnpackData::Slice(None),
            );
            for p in [glow017::TEXTURE_MIN_FILTER, glow017::TEXTURE_MAG_FILTER] {
                gl.tex_parameter_i32(glow017::TEXTURE_2D, p, glow017::NEAREST as i32);
            }
            let gbuffer = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(gbuffer));
            for layer in 0..2 {
                gl.framebuffer_texture_layer(
                    glow017::FRAMEBUFFER,
                    glow017::COLOR_ATTACHMENT0 + layer as u32,
                    Some(layers),
                    0,
                    layer,
                );
            }
            gl.framebuffer_texture_2d(
                glow017::FRAMEBUFFER,
                glow017::DEPTH_ATTACHMENT,
                glow017::TEXTURE_2D,
                Some(depth),
                0,
            );
            gl.draw_buffers(&[glow017::COLOR_ATTACHMENT0, glow017::COLOR_ATTACHMENT1]);
            if gl.check_framebuffer_status(glow017::FRAMEBUFFER) != glow017::FRAMEBUFFER_COMPLETE {
                return Err("the G-buffer is incomplete".into());
            }
            // The lit target.
            let lit_texture = gl.create_texture()?;
            gl.bind_texture(glow017::TEXTURE_2D, Some(lit_texture));
            gl.tex_image_2d(
                glow017::TEXTURE_2D,
                0,
                glow017::RGBA8 as i32,
                width,
                height,
                0,
                glow017::RGBA,
                glow017::UNSIGNED_BYTE,
                glow017::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow017::TEXTURE_2D, None);
            let lit = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(lit));
            gl.framebuffer_texture_2d(
                glow017::FRAMEBUFFER,
                glow017::COLOR_ATTACHMENT0,
                glow017::TEXTURE_2D,
                Some(lit_texture),
                0,
            );

            // The geometry pass.
            let mut target = gbuffer;
            if let Some(retrofit) = in_source.as_deref_mut() {
                target = glow017::NativeFramebuffer(retrofit.begin(gbuffer.0)?);
            }
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(target));
            gl.viewport(0, 0, width, height);
            gl.clear_buffer_f32_slice(glow017::COLOR, 0, &[0.0; 4]);
            gl.clear_buffer_f32_slice(glow017::COLOR, 1, &[0.0; 4]);
            gl.clear_buffer_f32_slice(glow017::DEPTH, 0, &[1.0]);
            gl.enable(glow017::DEPTH_TEST);
            gl.use_program(Some(self.geometry));
            let (projection, view) = Self::camera(width, height);
            let view_projection = projection * view;
            let at = |name: &str| gl.get_uniform_location(self.geometry, name);
            gl.uniform_matrix_4_f32_slice(
                at("viewProjection").as_ref(),
                false,
                &view_projection.to_cols_array(),
            );
            gl.bind_vertex_array(Some(self.cube));
            for o in &self.objects {
                gl.uniform_matrix_4_f32_slice(
                    at("model").as_ref(),
                    false,
                    &o.model.to_cols_array(),
                );
                gl.uniform_3_f32(at("albedo").as_ref(), o.albedo.x, o.albedo.y, o.albedo.z);
                gl.draw_arrays(glow017::TRIANGLES, 0, 36);
            }
            gl.disable(glow017::DEPTH_TEST);
            if let Some(retrofit) = in_source.as_deref_mut() {
                retrofit.resolve(projection)?;
            }

            // The lighting, into the lit target (and again into the crate's
            // own target for the second layer, in the source).
            self.lighting_into(lit, layers, width, height);
            if let Some(retrofit) = in_source {
                if let Some(own) = retrofit.begin_second_layer(lit.0)? {
                    self.lighting_into(glow017::NativeFramebuffer(own), layers, width, height);
                    retrofit.finish_second_layer(lit.0)?;
                }
            }

            // Read back, then everything deleted.
            let mut rgba = vec![0u8; (width * height * 4) as usize];
            gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, Some(lit));
            gl.read_pixels(
                0,
                0,
                width,
                height,
                glow017::RGBA,
                glow017::UNSIGNED_BYTE,
                glow017::PixelPackData::Slice(Some(&mut rgba)),
            );
            let mut depths = Vec::new();
            if want_depth {
                let mut bytes = vec![0u8; (width * height * 4) as usize];
                gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, Some(gbuffer));
                gl.read_pixels(
                    0,
                    0,
                    width,
                    height,
                    glow017::DEPTH_COMPONENT,
                    glow017::FLOAT,
                    glow017::PixelPackData::Slice(Some(&mut bytes)),
                );
                depths = bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
            }
            gl.bind_framebuffer(glow017::FRAMEBUFFER, None);
            gl.delete_framebuffer(lit);
            gl.delete_framebuffer(gbuffer);
            gl.delete_texture(lit_texture);
            gl.delete_texture(depth);
            gl.delete_texture(layers);
            let error = gl.get_error();
            if error != glow017::NO_ERROR {
                return Err(format!("GL error 0x{error:04X} in the render").into());
            }
            Ok(Image {
                rgba,
                depth: depths,
            })
        }
    }

    /// The lighting pass: a full-screen triangle reading the G-buffer's
    /// layers through the array.
    unsafe fn lighting_into(
        &self,
        target: glow017::Framebuffer,
        layers: glow017::Texture,
        width: i32,
        height: i32,
    ) {
        let gl = &self.gl;
        unsafe {
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(target));
            gl.viewport(0, 0, width, height);
            gl.use_program(Some(self.lighting));
            gl.active_texture(glow017::TEXTURE0);
            gl.bind_texture(glow017::TEXTURE_2D_ARRAY, Some(layers));
            let at = |name: &str| gl.get_uniform_location(self.lighting, name);
            gl.uniform_1_i32(at("gbuffer").as_ref(), 0);
            let sun = Vec3::new(0.4, 0.8, 0.45).normalize();
            gl.uniform_3_f32(at("sunDirection").as_ref(), sun.x, sun.y, sun.z);
            gl.uniform_2_f32(at("viewport").as_ref(), width as f32, height as f32);
            gl.bind_vertex_array(Some(self.empty));
            gl.draw_arrays(glow017::TRIANGLES, 0, 3);
            // The pass leaves nothing bound, as this engine's passes do.
            gl.bind_vertex_array(None);
            gl.bind_texture(glow017::TEXTURE_2D_ARRAY, None);
        }
    }

    unsafe fn destroy(self) {
        unsafe {
            self.gl.delete_program(self.geometry);
            self.gl.delete_program(self.lighting);
            self.gl.delete_vertex_array(self.cube);
            self.gl.delete_vertex_array(self.empty);
            self.gl.delete_buffer(self.cube_buffer);
        }
    }
}

/// The retrofit in the source (`--in-source`): made at the first call,
/// given each call's new G-buffer after.
struct InSource {
    load: Box<dyn FnMut(&str) -> *const std::ffi::c_void>,
    retrofit: Option<ForeignRetrofit>,
}

impl InSource {
    /// The options `tests/fast/inject/rust_engine.rs`'s profile states:
    /// the normal layer named and taken from one sample, two layers, the
    /// lit values display values (sRGB written by the shader).
    fn options() -> RetrofitOptions {
        let mut options = RetrofitOptions {
            normal_attachment: Some(NormalAttachment {
                attachment: ColorAttachment(1),
                encoding: deferred_msaa::resolve::NormalEncoding::Xyz,
            }),
            rules: vec![(
                ColorAttachment(1),
                deferred_msaa::resolve::ResolveRule::Select,
            )],
            layer_mix: LayerMix::SrgbEncoded,
            ..RetrofitOptions::default()
        };
        options.resolve.layers = 2;
        options
    }

    /// The framebuffer to draw the geometry into this call.
    fn begin(&mut self, gbuffer: NonZeroU32) -> Result<NonZeroU32> {
        match self.retrofit.as_mut() {
            Some(r) => r.refresh_with(gbuffer)?,
            None => {
                // SAFETY: the engine's context is current; the loader gives
                // its entry points.
                let made =
                    unsafe { ForeignRetrofit::new(&mut self.load, gbuffer, &Self::options())? };
                self.retrofit = Some(made);
            }
        }
        let retrofit = self.retrofit.as_mut().ok_or("no retrofit")?;
        Ok(retrofit.begin_frame()?)
    }

    fn resolve(&mut self, projection: Mat4) -> Result<()> {
        let retrofit = self.retrofit.as_mut().ok_or("no retrofit")?;
        Ok(retrofit.resolve(&Frame::from_matrix(projection.to_cols_array()))?)
    }

    fn begin_second_layer(&mut self, lit: NonZeroU32) -> Result<Option<NonZeroU32>> {
        let retrofit = self.retrofit.as_mut().ok_or("no retrofit")?;
        Ok(retrofit.begin_second_layer_own_target(Some(lit))?)
    }

    fn finish_second_layer(&mut self, lit: NonZeroU32) -> Result<()> {
        let retrofit = self.retrofit.as_mut().ok_or("no retrofit")?;
        Ok(retrofit.finish_second_layer(Some(lit))?)
    }
}

fn decode(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn encode(l: f64) -> u8 {
    let c = if l <= 0.0031308 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The 16x image (averaged in linear light) and the edge mask, from the
/// frame rendered at 4x the width and height.
fn reference(big: &Image) -> (Vec<u8>, Vec<u8>) {
    let (w, h, s) = (WIDTH as usize, HEIGHT as usize, SUPERSAMPLE as usize);
    let bw = w * s;
    let mut rgba = vec![0u8; w * h * 4];
    let mut edges = vec![0u8; w * h];
    let (near, far) = (0.1f64, 50.0f64);
    let distance = |d: f32| {
        let z = 2.0 * f64::from(d) - 1.0;
        2.0 * near * far / (far + near - z * (far - near))
    };
    for y in 0..h {
        for x in 0..w {
            let under = |dx: usize, dy: usize| (y * s + dy) * bw + x * s + dx;
            for c in 0..4 {
                let sum: f64 = (0..s * s)
                    .map(|k| {
                        let v = big.rgba[under(k % s, k / s) * 4 + c];
                        if c == 3 {
                            f64::from(v) / 255.0
                        } else {
                            decode(v)
                        }
                    })
                    .sum();
                let mean = sum / (s * s) as f64;
                rgba[(y * w + x) * 4 + c] = if c == 3 {
                    (mean * 255.0).round() as u8
                } else {
                    encode(mean)
                };
            }
            let depths: Vec<f32> = (0..s * s).map(|k| big.depth[under(k % s, k / s)]).collect();
            let sky = depths.iter().filter(|&&d| d >= 1.0).count();
            let geometry: Vec<f64> = depths
                .iter()
                .filter(|&&d| d < 1.0)
                .map(|&d| distance(d))
                .collect();
            let spread = match (
                geometry.iter().cloned().reduce(f64::min),
                geometry.iter().cloned().reduce(f64::max),
            ) {
                (Some(lo), Some(hi)) => (hi - lo) / lo,
                _ => 0.0,
            };
            if (sky > 0 && sky < s * s) || spread > 0.01 {
                edges[y * w + x] = 255;
            }
        }
    }
    (rgba, edges)
}

fn run() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let out = args
        .next()
        .ok_or("usage: inject_rust_engine OUT.rgba [--frames N] [--reference DIR] [--in-source]")?;
    let (mut frames, mut reference_dir, mut in_source) = (3u32, None, false);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--frames" => frames = args.next().ok_or("--frames needs a count")?.parse()?,
            "--reference" => reference_dir = Some(args.next().ok_or("--reference needs a folder")?),
            "--in-source" => in_source = true,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    if frames == 0 {
        return Err("--frames needs 1 or more".into());
    }
    // SAFETY: libEGL's entry points, as their names say.
    let egl = std::sync::Arc::new(
        unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }
            .map_err(|e| format!("libEGL: {e}"))?,
    );
    // SAFETY: a platform enum and the default display.
    let display = unsafe {
        egl.get_platform_display(
            EGL_PLATFORM_SURFACELESS_MESA,
            egl::DEFAULT_DISPLAY,
            &[egl::ATTRIB_NONE],
        )
    }?;
    egl.initialize(display)?;
    egl.bind_api(egl::OPENGL_API)?;
    let config = egl
        .choose_first_config(
            display,
            &[
                egl::SURFACE_TYPE,
                0,
                egl::RENDERABLE_TYPE,
                egl::OPENGL_BIT,
                egl::NONE,
            ],
        )?
        .ok_or("no EGL config for desktop OpenGL")?;
    let context = egl.create_context(
        display,
        config,
        None,
        &[
            egl::CONTEXT_MAJOR_VERSION,
            3,
            egl::CONTEXT_MINOR_VERSION,
            2,
            egl::CONTEXT_OPENGL_PROFILE_MASK,
            egl::CONTEXT_OPENGL_CORE_PROFILE_BIT,
            egl::NONE,
        ],
    )?;
    egl.make_current(display, None, None, Some(context))?;
    let load = {
        let egl = egl.clone();
        move |name: &str| {
            egl.get_proc_address(name)
                .map_or(std::ptr::null(), |f| f as *const std::ffi::c_void)
        }
    };
    // SAFETY: the context is current; the loader gives its entry points.
    let gl = unsafe { glow017::Context::from_loader_function(load.clone()) };
    println!("GL {}", unsafe {
        gl.get_parameter_string(glow017::VERSION)
    });
    // SAFETY: this thread's current context, for the rest of `run`.
    unsafe {
        let engine = Engine::new(gl)?;
        let mut retrofit = in_source.then(|| InSource {
            load: Box::new(load.clone()),
            retrofit: None,
        });
        let mut image = None;
        for _ in 0..frames {
            image = Some(engine.render(WIDTH, HEIGHT, retrofit.as_mut(), false)?);
        }
        let image = image.ok_or("no frame")?;
        std::fs::write(&out, &image.rgba).map_err(|e| format!("{out}: {e}"))?;
        if let Some(r) = retrofit.and_then(|r| r.retrofit) {
            r.destroy();
        }
        if let Some(dir) = reference_dir {
            let big = engine.render(WIDTH * SUPERSAMPLE, HEIGHT * SUPERSAMPLE, None, true)?;
            let (rgba, edges) = reference(&big);
            let dir = std::path::Path::new(&dir);
            std::fs::write(dir.join("reference.rgba"), rgba)?;
            std::fs::write(dir.join("edges.mask"), edges)?;
        }
        engine.destroy();
    }
    egl.make_current(display, None, None, None)?;
    egl.destroy_context(display, context)?;
    egl.terminate(display)?;
    println!("ok");
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("inject_rust_engine: {e}");
            ExitCode::FAILURE
        }
    }
}
