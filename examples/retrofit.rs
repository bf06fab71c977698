//! Retrofitting depth-aware MSAA into an existing deferred renderer.
//!
//! `Engine` below is a small deferred renderer written the way engines are
//! written, with raw OpenGL and no knowledge of this crate: its own G-buffer
//! FBO (albedo + metalness RGBA8, normal + roughness RGBA16F, emission
//! R11F_G11F_B10F, DEPTH24_STENCIL8), its own model shader, and its own
//! lighting shader, which reconstructs the view-space position from depth
//! and draws the sky where nothing was drawn.
//!
//! MSAA is added to it by exactly these lines (marked `MSAA` in `main`):
//!
//! ```text
//! let mut msaa = MsaaRetrofit::new(gl, engine.gbuffer_fbo(), &RetrofitOptions {  // once
//!     samples, rules: vec![(ColorAttachment(1), Select), (ColorAttachment(2), BlendHdr)],
//!     ..RetrofitOptions::default()                // no position target: the key is linearised depth
//! })?;
//! engine.geometry_pass(gl, msaa.begin_frame(gl)?);  // was: engine.geometry_pass(gl, engine.gbuffer_fbo())
//! msaa.resolve(gl, &Frame::from_matrix(engine.projection().to_cols_array()))?;  // into its textures
//! msaa.destroy(gl);                               // at shutdown
//! ```
//!
//! The model shader, the lighting shader and the G-buffer stay as they were.
//! The scene comes from the crate's scene loader (a built-in scene or a glTF
//! file: plain CPU data), uploaded by the engine itself; the engine draws
//! base colour, metalness, roughness and emission factors, not textures.
//!
//! ```sh
//! cargo run --release --example retrofit -- [OUT.png] [--scene builtin:greebles|FILE.gltf]
//!     [--size 640x360] [--samples 4] [--method none|average|front|median|back]
//! ```
//! The image goes to `target/retrofit.png` unless a path is given.

use std::error::Error;
use std::process::ExitCode;

use deferred_msaa::resolve::{ResolveMethod, ResolveRule, ResolveSettings};
use deferred_msaa::{ColorAttachment, Frame, MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::cli::{Printed, parse_args};
use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::scene::{AlphaMode, Background, LightKind, Scene};
use glam::{Mat3, Mat4, Vec3};
use glow::HasContext;

type AnyResult<T> = Result<T, Box<dyn Error>>;

fn main() -> ExitCode {
    let args = match parse_args::<Args>() {
        Ok(args) => args,
        Err(Printed::Help) => return ExitCode::SUCCESS,
        Err(Printed::UsageError) => return ExitCode::FAILURE,
    };
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("retrofit: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> AnyResult<()> {
    let (width, height) = args.size;
    let method = match args.method.as_str() {
        "none" => None,
        name => Some(name.parse::<ResolveMethod>()?),
    };
    let scene = Scene::load(&args.scene)?;
    let context = HeadlessContext::new(Backend::Egl)?;
    let gl = context.gl();
    // Once per process: the per-draw-buffer queries glow does not wrap, so
    // that the retrofit keeps the engine's per-buffer blend and masks.
    deferred_msaa::gl::load_state_functions(|name| context.get_proc_address(name))?;

    let engine = Engine::new(gl, &scene, width, height)?;
    let image = match method {
        None => {
            // The engine as it was: no MSAA.
            engine.geometry_pass(gl, engine.gbuffer_fbo())?;
            engine.lighting_pass(gl)?;
            engine.read_output(gl)?
        }
        Some(method) => {
            // MSAA (1 of 4): multisampled twins of the engine's G-buffer.
            let mut msaa = MsaaRetrofit::new(
                gl,
                engine.gbuffer_fbo(),
                &RetrofitOptions {
                    samples: args.samples,
                    // Normals from the reference sample, as the crate's
                    // recommended layout takes them (a blended, renormalised
                    // normal over-lights convex edges; see
                    // `GBufferLayout::recommended`); emission blended as HDR.
                    rules: vec![
                        (ColorAttachment(1), ResolveRule::Select),
                        (ColorAttachment(2), ResolveRule::BlendHdr),
                    ],
                    resolve: ResolveSettings {
                        method,
                        ..ResolveSettings::default()
                    },
                    ..RetrofitOptions::default()
                },
            )?;
            let result = (|| -> AnyResult<image::RgbaImage> {
                // MSAA (2 of 4): the unchanged geometry pass draws into the twins.
                engine.geometry_pass(gl, msaa.begin_frame(gl)?)?;
                // MSAA (3 of 4): resolve into the engine's own G-buffer textures.
                msaa.resolve(gl, &Frame::from_matrix(engine.projection().to_cols_array()))?;
                // The unchanged lighting pass reads the resolved G-buffer.
                engine.lighting_pass(gl)?;
                engine.read_output(gl)
            })();
            println!("{}x MSAA ({})", msaa.samples(), method.name());
            // MSAA (4 of 4): free the twins and the resolve program.
            msaa.destroy(gl);
            result?
        }
    };
    engine.destroy(gl);

    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    image
        .save(&args.out)
        .map_err(|e| format!("cannot write {}: {e}", args.out.display()))?;
    println!(
        "{} ({}x{}) -> {}",
        scene.name,
        width,
        height,
        args.out.display()
    );
    Ok(())
}

/// The command line.
#[derive(clap::Parser)]
#[command(
    name = "retrofit",
    about = "An engine's deferred renderer with depth-aware MSAA retrofitted by four lines"
)]
struct Args {
    /// Where the image goes.
    #[arg(default_value = "target/retrofit.png")]
    out: std::path::PathBuf,
    /// A built-in scene (`builtin:NAME`) or a glTF file.
    #[arg(long, default_value = "builtin:greebles")]
    scene: String,
    /// The image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel asked for (the driver's real count is used).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    samples: u32,
    /// `none` (the engine as it was) or the resolve method.
    #[arg(long, default_value = "median", value_parser = ["none", "average", "front", "median", "back"])]
    method: String,
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parsed = text
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w > 0 && h > 0 && w <= 16384 && h <= 16384 => Ok((w, h)),
        _ => Err(format!(
            "expected WIDTHxHEIGHT such as 640x360, got `{text}`"
        )),
    }
}

// ---------------------------------------------------------------------------
// The host engine. Nothing below knows about MSAA.

const MODEL_VERT: &str = r#"#version 150 core
in vec3 a_position;
in vec3 a_normal;
uniform mat4 u_model_view;
uniform mat3 u_normal_matrix;
uniform mat4 u_projection;
out vec3 v_normal;
void main() {
    v_normal = u_normal_matrix * a_normal;
    gl_Position = u_projection * (u_model_view * vec4(a_position, 1.0));
}
"#;

const MODEL_FRAG: &str = r#"#version 150 core
in vec3 v_normal;
uniform vec3 u_albedo;
uniform float u_metallic;
uniform float u_roughness;
uniform vec3 u_emission;
uniform int u_two_sided;
out vec4 o_albedo_metal;   // GL_COLOR_ATTACHMENT0
out vec4 o_normal_rough;   // GL_COLOR_ATTACHMENT1
out vec4 o_emission;       // GL_COLOR_ATTACHMENT2
void main() {
    float len = length(v_normal);
    vec3 n = len > 1e-8 ? v_normal / len : vec3(0.0, 0.0, 1.0);
    if (u_two_sided != 0 && !gl_FrontFacing) {
        n = -n;
    }
    o_albedo_metal = vec4(u_albedo, clamp(u_metallic, 0.0, 1.0));
    o_normal_rough = vec4(n, clamp(u_roughness, 0.0, 1.0));
    o_emission = vec4(u_emission, 1.0);
}
"#;

/// A triangle covering the screen, from `gl_VertexID` alone.
const FULLSCREEN_VERT: &str = r#"#version 150 core
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

/// Per-pixel lighting from the G-buffer, then tonemapping, in one pass.
/// Metallic-roughness: GGX distribution, Schlick-GGX visibility, Schlick
/// Fresnel, Lambert diffuse, a constant ambient term; point, spot and
/// directional lights with inverse-square fall-off windowed to their range.
const LIGHTING_FRAG: &str = r#"#version 150 core
#define MAX_LIGHTS 32
#define PI 3.14159265358979
uniform sampler2D u_albedo_metal;
uniform sampler2D u_normal_rough;
uniform sampler2D u_emission;
uniform sampler2D u_depth;
uniform vec2 u_viewport;
uniform vec4 u_projection;        // P[0][0], P[1][1], P[2][2], P[3][2]
uniform mat3 u_view_to_world;
uniform int u_sky;                // 0: black, 1: gradient
uniform vec3 u_zenith;
uniform vec3 u_horizon;
uniform vec3 u_ambient;
uniform int u_light_count;
uniform vec4 u_light_position[MAX_LIGHTS];   // view space, w = range (0: none)
uniform vec4 u_light_direction[MAX_LIGHTS];  // view space, w = 0 point, 1 spot, 2 directional
uniform vec4 u_light_color[MAX_LIGHTS];      // colour x intensity
uniform vec4 u_light_cone[MAX_LIGHTS];       // cos(outer), cos(inner)
out vec4 o_color;

vec3 sky(vec2 ndc) {
    if (u_sky == 0) {
        return vec3(0.0);
    }
    vec3 view_dir = normalize(vec3(ndc.x / u_projection.x, ndc.y / u_projection.y, -1.0));
    vec3 dir = normalize(u_view_to_world * view_dir);
    return mix(u_horizon, u_zenith, clamp(dir.y, 0.0, 1.0));
}

vec3 tonemap(vec3 hdr) {
    const float white = 8.0;
    hdr = clamp(mix(hdr, vec3(0.0), isnan(hdr)), 0.0, white);
    vec3 ldr = clamp(hdr * (1.0 + hdr / (white * white)) / (1.0 + hdr), 0.0, 1.0);
    vec3 srgb_low = ldr * 12.92;
    vec3 srgb_high = 1.055 * pow(ldr, vec3(1.0 / 2.4)) - 0.055;
    return mix(srgb_low, srgb_high, step(vec3(0.0031308), ldr));
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 ndc = gl_FragCoord.xy / u_viewport * 2.0 - 1.0;
    float depth = texelFetch(u_depth, pixel, 0).r;
    if (depth == 1.0) {
        o_color = vec4(tonemap(sky(ndc)), 1.0);
        return;
    }
    // View-space position from the depth buffer.
    float dist = u_projection.w / ((2.0 * depth - 1.0) + u_projection.z);
    vec3 p = vec3(ndc.x * dist / u_projection.x, ndc.y * dist / u_projection.y, -dist);

    vec4 albedo_metal = texelFetch(u_albedo_metal, pixel, 0);
    vec4 normal_rough = texelFetch(u_normal_rough, pixel, 0);
    vec3 base = albedo_metal.rgb;
    float metallic = albedo_metal.a;
    float len = length(normal_rough.xyz);
    vec3 n = len > 1e-6 ? normal_rough.xyz / len : vec3(0.0, 0.0, 1.0);
    vec3 v = normalize(-p);
    vec3 f0 = mix(vec3(0.04), base, metallic);
    float roughness = clamp(normal_rough.w, 0.03, 1.0);
    float alpha = roughness * roughness;
    float alpha2 = alpha * alpha;
    float k = alpha * 0.5;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    float vis_v = n_dot_v / (n_dot_v * (1.0 - k) + k);
    vec3 diffuse = base * (1.0 - metallic) / PI;

    vec3 radiance = texelFetch(u_emission, pixel, 0).rgb + u_ambient * (base * (1.0 - metallic) + f0);
    for (int i = 0; i < u_light_count; ++i) {
        int kind = int(u_light_direction[i].w + 0.5);
        vec3 l;
        float falloff = 1.0;
        if (kind == 2) {
            l = -u_light_direction[i].xyz;
        } else {
            vec3 to_light = u_light_position[i].xyz - p;
            float d2 = max(dot(to_light, to_light), 1e-8);
            float d = sqrt(d2);
            l = to_light / d;
            falloff = 1.0 / d2;
            float range = u_light_position[i].w;
            if (range > 0.0) {
                float r = d / range;
                float window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
                falloff *= window * window;
            }
            if (kind == 1) {
                float cos_outer = u_light_cone[i].x;
                float cos_inner = u_light_cone[i].y;
                float t = clamp((dot(-l, u_light_direction[i].xyz) - cos_outer)
                                / max(cos_inner - cos_outer, 1e-4), 0.0, 1.0);
                falloff *= t * t;
            }
        }
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0 || falloff <= 0.0) {
            continue;
        }
        vec3 h = normalize(l + v);
        float n_dot_h = max(dot(n, h), 0.0);
        float v_dot_h = max(dot(v, h), 0.0);
        float denom = n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0;
        float distribution = alpha2 / (PI * denom * denom);
        float vis_l = n_dot_l / (n_dot_l * (1.0 - k) + k);
        float visibility = vis_l * vis_v / (4.0 * n_dot_l * n_dot_v);
        vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - v_dot_h, 5.0);
        vec3 brdf = (1.0 - fresnel) * diffuse + fresnel * (distribution * visibility);
        radiance += brdf * u_light_color[i].rgb * (falloff * n_dot_l);
    }
    o_color = vec4(tonemap(radiance), 1.0);
}
"#;

const MAX_LIGHTS: usize = 32;
const AMBIENT: [f32; 3] = [0.03, 0.03, 0.035];

/// One uploaded object.
struct Mesh {
    vao: glow::VertexArray,
    buffers: [glow::Buffer; 2],
    index_count: i32,
    model: Mat4,
    albedo: [f32; 3],
    metallic: f32,
    roughness: f32,
    emission: [f32; 3],
    two_sided: bool,
}

/// A texture and the framebuffer drawing into it.
struct Target {
    texture: glow::Texture,
    fbo: glow::Framebuffer,
}

/// The host engine: a deferred renderer with its own G-buffer and shaders.
struct Engine {
    width: u32,
    height: u32,
    view: Mat4,
    projection: Mat4,
    sky: Option<([f32; 3], [f32; 3])>,
    /// View-space lights: position + range, direction + kind, colour, cone.
    lights: Vec<[[f32; 4]; 4]>,
    meshes: Vec<Mesh>,
    /// albedo + metalness, normal + roughness, emission, depth-stencil.
    gbuffer_textures: [glow::Texture; 4],
    gbuffer_fbo: glow::Framebuffer,
    output: Target,
    model_program: glow::Program,
    lighting_program: glow::Program,
    empty_vao: glow::VertexArray,
}

impl Engine {
    fn new(gl: &glow::Context, scene: &Scene, width: u32, height: u32) -> AnyResult<Engine> {
        let projection = scene.camera.projection(width as f32 / height as f32);
        let view = scene.camera.view;
        if scene.lights.len() > MAX_LIGHTS {
            eprintln!(
                "retrofit: the engine lights {MAX_LIGHTS} of the scene's {} lights",
                scene.lights.len()
            );
        }
        let lights = scene
            .lights
            .iter()
            .take(MAX_LIGHTS)
            .map(|light| {
                let p = view.transform_point3(light.position);
                let d = view
                    .transform_vector3(light.direction)
                    .normalize_or(Vec3::NEG_Z);
                let range = light
                    .range
                    .filter(|r| r.is_finite() && *r > 0.0)
                    .unwrap_or(0.0);
                let (kind, cone) = match light.kind {
                    LightKind::Point => (0.0, [0.0; 4]),
                    LightKind::Spot {
                        inner_cone,
                        outer_cone,
                    } => (1.0, [outer_cone.cos(), inner_cone.cos(), 0.0, 0.0]),
                    LightKind::Directional => (2.0, [0.0; 4]),
                };
                let c = light.color * light.intensity;
                [
                    [p.x, p.y, p.z, range],
                    [d.x, d.y, d.z, kind],
                    [c.x, c.y, c.z, 0.0],
                    cone,
                ]
            })
            .collect();
        let sky = match scene.background {
            Background::Gradient { zenith, horizon } => Some((zenith, horizon)),
            // This engine's sky is a gradient or nothing.
            Background::Black | Background::Stars { .. } => None,
        };

        unsafe {
            let model_program = build_program(
                gl,
                MODEL_VERT,
                MODEL_FRAG,
                &[("a_position", 0), ("a_normal", 1)],
                &[
                    ("o_albedo_metal", 0),
                    ("o_normal_rough", 1),
                    ("o_emission", 2),
                ],
            )?;
            let lighting_program =
                build_program(gl, FULLSCREEN_VERT, LIGHTING_FRAG, &[], &[("o_color", 0)])?;
            let empty_vao = gl.create_vertex_array()?;

            // The G-buffer, as an engine allocates it.
            let formats = [
                (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE),
                (glow::RGBA16F, glow::RGBA, glow::HALF_FLOAT),
                (glow::R11F_G11F_B10F, glow::RGB, glow::HALF_FLOAT),
                (
                    glow::DEPTH24_STENCIL8,
                    glow::DEPTH_STENCIL,
                    glow::UNSIGNED_INT_24_8,
                ),
            ];
            let mut textures = Vec::new();
            for (internal, format, ty) in formats {
                textures.push(create_texture(gl, width, height, internal, format, ty)?);
            }
            let gbuffer_textures = [textures[0], textures[1], textures[2], textures[3]];
            let gbuffer_fbo = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(gbuffer_fbo));
            for (i, &t) in gbuffer_textures[..3].iter().enumerate() {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::COLOR_ATTACHMENT0 + i as u32,
                    glow::TEXTURE_2D,
                    Some(t),
                    0,
                );
            }
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(gbuffer_textures[3]),
                0,
            );
            gl.draw_buffers(&[
                glow::COLOR_ATTACHMENT0,
                glow::COLOR_ATTACHMENT1,
                glow::COLOR_ATTACHMENT2,
            ]);
            check_complete(gl, "G-buffer")?;

            let output_texture = create_texture(
                gl,
                width,
                height,
                glow::RGBA8,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
            )?;
            let output_fbo = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(output_fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(output_texture),
                0,
            );
            check_complete(gl, "output")?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);

            let mut meshes = Vec::new();
            for object in &scene.objects {
                let material = scene.material_of(object);
                if material.alpha_mode == AlphaMode::Blend {
                    continue; // this engine has no forward pass for transparent objects
                }
                let mut vertices = Vec::with_capacity(object.positions.len() * 6);
                for (p, n) in object.positions.iter().zip(&object.normals) {
                    vertices.extend_from_slice(p);
                    vertices.extend_from_slice(n);
                }
                let vao = gl.create_vertex_array()?;
                let vbo = gl.create_buffer()?;
                let ibo = gl.create_buffer()?;
                gl.bind_vertex_array(Some(vao));
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
                gl.buffer_data_u8_slice(
                    glow::ARRAY_BUFFER,
                    bytemuck::cast_slice(&vertices),
                    glow::STATIC_DRAW,
                );
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ibo));
                gl.buffer_data_u8_slice(
                    glow::ELEMENT_ARRAY_BUFFER,
                    bytemuck::cast_slice(&object.indices),
                    glow::STATIC_DRAW,
                );
                gl.enable_vertex_attrib_array(0);
                gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 24, 0);
                gl.enable_vertex_attrib_array(1);
                gl.vertex_attrib_pointer_f32(1, 3, glow::FLOAT, false, 24, 12);
                gl.bind_vertex_array(None);
                let b = material.base_color;
                meshes.push(Mesh {
                    vao,
                    buffers: [vbo, ibo],
                    index_count: object.indices.len() as i32,
                    model: object.transform,
                    albedo: [b[0], b[1], b[2]],
                    metallic: material.metallic,
                    roughness: material.roughness,
                    emission: material.emissive,
                    two_sided: material.double_sided,
                });
            }
            gl_ok(gl, "creating the engine")?;
            Ok(Engine {
                width,
                height,
                view,
                projection,
                sky,
                lights,
                meshes,
                gbuffer_textures,
                gbuffer_fbo,
                output: Target {
                    texture: output_texture,
                    fbo: output_fbo,
                },
                model_program,
                lighting_program,
                empty_vao,
            })
        }
    }

    fn gbuffer_fbo(&self) -> glow::Framebuffer {
        self.gbuffer_fbo
    }

    fn projection(&self) -> Mat4 {
        self.projection
    }

    /// Draw every opaque object into `fbo` (the G-buffer, normally).
    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) -> AnyResult<()> {
        let p = self.model_program;
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.disable(glow::BLEND);
            gl.disable(glow::SCISSOR_TEST);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            gl.color_mask(true, true, true, true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.front_face(glow::CCW);
            gl.use_program(Some(p));
            let uniform = |name: &str| gl.get_uniform_location(p, name);
            gl.uniform_matrix_4_f32_slice(
                uniform("u_projection").as_ref(),
                false,
                &self.projection.to_cols_array(),
            );
            for mesh in &self.meshes {
                let model_view = self.view * mesh.model;
                let normal = Mat3::from_mat4(model_view).inverse().transpose();
                let normal = if normal.is_finite() {
                    normal
                } else {
                    Mat3::IDENTITY
                };
                gl.uniform_matrix_4_f32_slice(
                    uniform("u_model_view").as_ref(),
                    false,
                    &model_view.to_cols_array(),
                );
                gl.uniform_matrix_3_f32_slice(
                    uniform("u_normal_matrix").as_ref(),
                    false,
                    &normal.to_cols_array(),
                );
                gl.uniform_3_f32_slice(uniform("u_albedo").as_ref(), &mesh.albedo);
                gl.uniform_1_f32(uniform("u_metallic").as_ref(), mesh.metallic);
                gl.uniform_1_f32(uniform("u_roughness").as_ref(), mesh.roughness);
                gl.uniform_3_f32_slice(uniform("u_emission").as_ref(), &mesh.emission);
                gl.uniform_1_i32(uniform("u_two_sided").as_ref(), mesh.two_sided as i32);
                if mesh.two_sided {
                    gl.disable(glow::CULL_FACE);
                } else {
                    gl.enable(glow::CULL_FACE);
                    gl.cull_face(glow::BACK);
                }
                gl.bind_vertex_array(Some(mesh.vao));
                gl.draw_elements(glow::TRIANGLES, mesh.index_count, glow::UNSIGNED_INT, 0);
            }
            gl.bind_vertex_array(None);
            gl.disable(glow::CULL_FACE);
        }
        gl_ok(gl, "the geometry pass")
    }

    /// Light the G-buffer into the output image.
    fn lighting_pass(&self, gl: &glow::Context) -> AnyResult<()> {
        let p = self.lighting_program;
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.output.fbo));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::CULL_FACE);
            gl.use_program(Some(p));
            let uniform = |name: &str| gl.get_uniform_location(p, name);
            let inputs = ["u_albedo_metal", "u_normal_rough", "u_emission", "u_depth"];
            for (unit, (name, texture)) in inputs.iter().zip(self.gbuffer_textures).enumerate() {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(texture));
                gl.uniform_1_i32(uniform(name).as_ref(), unit as i32);
            }
            gl.uniform_2_f32(
                uniform("u_viewport").as_ref(),
                self.width as f32,
                self.height as f32,
            );
            let m = self.projection;
            gl.uniform_4_f32(
                uniform("u_projection").as_ref(),
                m.x_axis.x,
                m.y_axis.y,
                m.z_axis.z,
                m.w_axis.z,
            );
            let view_to_world = Mat3::from_mat4(self.view).transpose();
            gl.uniform_matrix_3_f32_slice(
                uniform("u_view_to_world").as_ref(),
                false,
                &view_to_world.to_cols_array(),
            );
            let (zenith, horizon) = self.sky.unwrap_or_default();
            gl.uniform_1_i32(uniform("u_sky").as_ref(), self.sky.is_some() as i32);
            gl.uniform_3_f32_slice(uniform("u_zenith").as_ref(), &zenith);
            gl.uniform_3_f32_slice(uniform("u_horizon").as_ref(), &horizon);
            gl.uniform_3_f32_slice(uniform("u_ambient").as_ref(), &AMBIENT);
            gl.uniform_1_i32(uniform("u_light_count").as_ref(), self.lights.len() as i32);
            for (field, name) in [
                "u_light_position",
                "u_light_direction",
                "u_light_color",
                "u_light_cone",
            ]
            .iter()
            .enumerate()
            {
                let values: Vec<f32> = self.lights.iter().flat_map(|l| l[field]).collect();
                if !values.is_empty() {
                    gl.uniform_4_f32_slice(uniform(&format!("{name}[0]")).as_ref(), &values);
                }
            }
            gl.bind_vertex_array(Some(self.empty_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            for unit in 0..inputs.len() as u32 {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, None);
            }
            gl.active_texture(glow::TEXTURE0);
        }
        gl_ok(gl, "the lighting pass")
    }

    /// The output image, top row first.
    fn read_output(&self, gl: &glow::Context) -> AnyResult<image::RgbaImage> {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut pixels = vec![0u8; w * h * 4];
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.output.fbo));
            gl.read_buffer(glow::COLOR_ATTACHMENT0);
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
            gl.read_pixels(
                0,
                0,
                w as i32,
                h as i32,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut pixels)),
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        gl_ok(gl, "reading the image")?;
        let rows: Vec<u8> = pixels
            .chunks_exact(w * 4)
            .rev()
            .flatten()
            .copied()
            .collect();
        image::RgbaImage::from_raw(self.width, self.height, rows)
            .ok_or_else(|| "image size mismatch".into())
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            for mesh in self.meshes {
                gl.delete_vertex_array(mesh.vao);
                for b in mesh.buffers {
                    gl.delete_buffer(b);
                }
            }
            gl.delete_framebuffer(self.gbuffer_fbo);
            gl.delete_framebuffer(self.output.fbo);
            for t in self.gbuffer_textures {
                gl.delete_texture(t);
            }
            gl.delete_texture(self.output.texture);
            gl.delete_program(self.model_program);
            gl.delete_program(self.lighting_program);
            gl.delete_vertex_array(self.empty_vao);
        }
    }
}

/// # Safety
/// A context must be current.
unsafe fn create_texture(
    gl: &glow::Context,
    width: u32,
    height: u32,
    internal: u32,
    format: u32,
    ty: u32,
) -> AnyResult<glow::Texture> {
    unsafe {
        let t = gl.create_texture()?;
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MIN_FILTER,
            glow::NEAREST as i32,
        );
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MAG_FILTER,
            glow::NEAREST as i32,
        );
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MAX_LEVEL, 0);
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            internal as i32,
            width as i32,
            height as i32,
            0,
            format,
            ty,
            glow::PixelUnpackData::Slice(None),
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
        Ok(t)
    }
}

/// # Safety
/// A context must be current.
unsafe fn build_program(
    gl: &glow::Context,
    vertex: &str,
    fragment: &str,
    attributes: &[(&str, u32)],
    outputs: &[(&str, u32)],
) -> AnyResult<glow::Program> {
    unsafe {
        let program = gl.create_program()?;
        let mut shaders = Vec::new();
        for (stage, source) in [
            (glow::VERTEX_SHADER, vertex),
            (glow::FRAGMENT_SHADER, fragment),
        ] {
            let shader = gl.create_shader(stage)?;
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            if !gl.get_shader_compile_status(shader) {
                let log = gl.get_shader_info_log(shader);
                gl.delete_shader(shader);
                gl.delete_program(program);
                return Err(format!("shader compilation failed: {}", log.trim()).into());
            }
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        for &(name, location) in attributes {
            gl.bind_attrib_location(program, location, name);
        }
        for &(name, location) in outputs {
            gl.bind_frag_data_location(program, location, name);
        }
        gl.link_program(program);
        for shader in shaders {
            gl.detach_shader(program, shader);
            gl.delete_shader(shader);
        }
        if !gl.get_program_link_status(program) {
            let log = gl.get_program_info_log(program);
            gl.delete_program(program);
            return Err(format!("program link failed: {}", log.trim()).into());
        }
        Ok(program)
    }
}

/// # Safety
/// A context must be current and the framebuffer bound.
unsafe fn check_complete(gl: &glow::Context, what: &str) -> AnyResult<()> {
    let status = unsafe { gl.check_framebuffer_status(glow::FRAMEBUFFER) };
    if status == glow::FRAMEBUFFER_COMPLETE {
        Ok(())
    } else {
        Err(format!("the {what} framebuffer is incomplete (status 0x{status:04X})").into())
    }
}

fn gl_ok(gl: &glow::Context, what: &str) -> AnyResult<()> {
    match unsafe { gl.get_error() } {
        glow::NO_ERROR => Ok(()),
        code => Err(format!("GL error 0x{code:04X} in {what}").into()),
    }
}
