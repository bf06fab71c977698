//! A PBR engine's compact G-buffer, the layout of engines that pack for
//! bandwidth: base colour in `GL_SRGB8_ALPHA8` (metalness in alpha)
//! written through `GL_FRAMEBUFFER_SRGB`, which the engine enables once at
//! start-up and leaves on; world-space normals octahedrally encoded in
//! `GL_RG16_SNORM`; an integer material id in `GL_R8UI` (0 = sky) that
//! indexes a roughness table; depth in `GL_DEPTH_COMPONENT32F`. The
//! lighting reads everything with `texelFetch` (the id through a
//! `usampler2D`), reconstructs the world position with the inverse
//! view-projection, and shades GGX with Schlick Fresnel. Back faces are
//! culled (`GL_CULL_FACE` stays on).

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::{NormalEncoding, ResolveRule};
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 a_position;
layout (location = 1) in vec3 a_normal;
layout (location = 2) in vec3 a_base_color;
layout (location = 3) in float a_material;
uniform mat4 u_view_projection;
flat out vec3 v_normal;
flat out vec3 v_base_color;
flat out uint v_material;
void main() {
    v_normal = a_normal;
    v_base_color = a_base_color;
    v_material = uint(a_material);
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
"#;

const MODEL_FS: &str = r#"#version 330 core
flat in vec3 v_normal;
flat in vec3 v_base_color;
flat in uint v_material;
layout (location = 0) out vec4 o_base_color_metal;
layout (location = 1) out vec2 o_normal_oct;
layout (location = 2) out uint o_material;

vec2 sign_not_zero(vec2 v) {
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    return n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * sign_not_zero(n.xy);
}

void main() {
    // Linear colour: GL_FRAMEBUFFER_SRGB encodes it into the sRGB target.
    o_base_color_metal = vec4(v_base_color, v_material == 3u ? 1.0 : 0.0);
    o_normal_oct = oct_encode(normalize(v_normal));
    o_material = v_material;
}
"#;

const FULLSCREEN_VS: &str = r#"#version 330 core
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const LIGHTING_FS: &str = r#"#version 330 core
#define PI 3.14159265
uniform sampler2D g_base_color_metal;
uniform sampler2D g_normal_oct;
uniform usampler2D g_material;
uniform sampler2D g_depth;
uniform mat4 u_inverse_view_projection;
uniform vec3 u_camera;
uniform vec2 u_size;
uniform float u_roughness[4];
uniform vec3 u_light_position[2];
uniform vec3 u_light_color[2];
out vec4 o_color;

vec3 oct_decode(vec2 f) {
    vec3 n = vec3(f.x, f.y, 1.0 - abs(f.x) - abs(f.y));
    float t = clamp(-n.z, 0.0, 1.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint material = texelFetch(g_material, p, 0).r;
    if (material == 0u) {
        o_color = vec4(pow(vec3(0.4, 0.55, 0.8), vec3(1.0 / 2.2)), 1.0);
        return;
    }
    float depth = texelFetch(g_depth, p, 0).r;
    vec4 ndc = vec4(gl_FragCoord.xy / u_size * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec4 world = u_inverse_view_projection * ndc;
    vec3 pos = world.xyz / world.w;
    vec4 base_metal = texelFetch(g_base_color_metal, p, 0);
    vec3 n = oct_decode(texelFetch(g_normal_oct, p, 0).xy);
    vec3 v = normalize(u_camera - pos);
    float roughness = u_roughness[min(material, 3u)];
    float a2 = roughness * roughness * roughness * roughness;
    vec3 f0 = mix(vec3(0.04), base_metal.rgb, base_metal.a);
    vec3 c = base_metal.rgb * 0.08;
    for (int i = 0; i < 2; ++i) {
        vec3 l = u_light_position[i] - pos;
        float d2 = dot(l, l);
        l = normalize(l);
        vec3 h = normalize(l + v);
        float nl = max(dot(n, l), 0.0);
        float nv = max(dot(n, v), 1e-4);
        float nh = max(dot(n, h), 0.0);
        float den = nh * nh * (a2 - 1.0) + 1.0;
        float d = a2 / (PI * den * den);
        float k = roughness * roughness * 0.5;
        float g = nl / (nl * (1.0 - k) + k) * nv / (nv * (1.0 - k) + k);
        vec3 f = f0 + (1.0 - f0) * pow(1.0 - max(dot(h, v), 0.0), 5.0);
        vec3 spec = d * g * f / max(4.0 * nl * nv, 1e-4);
        vec3 diffuse = (1.0 - f) * (1.0 - base_metal.a) * base_metal.rgb / PI;
        c += (diffuse + spec) * u_light_color[i] * 12.0 * nl / (1.0 + d2);
    }
    c = c / (1.0 + c);
    o_color = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}
"#;

/// The PBR engine.
pub struct PbrEngine {
    width: i32,
    height: i32,
    gbuffer: glow::Framebuffer,
    base_color: glow::Texture,
    normal: glow::Texture,
    material: glow::Texture,
    depth: glow::Texture,
    screen: glow::Framebuffer,
    screen_color: glow::Texture,
    model: glow::Program,
    lighting: glow::Program,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    count: i32,
    empty_vao: glow::VertexArray,
}

impl PbrEngine {
    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(scene::projection(self.width as u32, self.height as u32).to_cols_array())
    }
}

impl ZooHost for PbrEngine {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            let texture = |internal: u32| {
                let t = gl.create_texture().unwrap();
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.tex_storage_2d(glow::TEXTURE_2D, 1, internal, w, h);
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
                t
            };
            let base_color = texture(glow::SRGB8_ALPHA8);
            let normal = texture(glow::RG16_SNORM);
            let material = texture(glow::R8UI);
            let depth = texture(glow::DEPTH_COMPONENT32F);
            let screen_color = texture(glow::RGBA8);
            let gbuffer = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(gbuffer));
            for (point, t) in [
                (glow::COLOR_ATTACHMENT0, base_color),
                (glow::COLOR_ATTACHMENT1, normal),
                (glow::COLOR_ATTACHMENT2, material),
                (glow::DEPTH_ATTACHMENT, depth),
            ] {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(t), 0);
            }
            gl.draw_buffers(&[
                glow::COLOR_ATTACHMENT0,
                glow::COLOR_ATTACHMENT1,
                glow::COLOR_ATTACHMENT2,
            ]);
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            let screen = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(screen));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(screen_color),
                0,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);

            let model = harness::program(gl, "pbr model", MODEL_VS, MODEL_FS);
            let lighting = harness::program(gl, "pbr lighting", FULLSCREEN_VS, LIGHTING_FS);
            let mut data: Vec<f32> = Vec::new();
            for f in scene::faces() {
                for c in f.corners {
                    data.extend_from_slice(&c.to_array());
                    data.extend_from_slice(&f.normal.to_array());
                    data.extend_from_slice(&f.colour.to_array());
                    data.push(f.material as f32);
                }
            }
            let vao = gl.create_vertex_array().unwrap();
            let vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&data),
                glow::STATIC_DRAW,
            );
            for (loc, size, offset) in [(0, 3, 0), (1, 3, 12), (2, 3, 24), (3, 1, 36)] {
                gl.enable_vertex_attrib_array(loc);
                gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, 40, offset);
            }
            gl.bind_vertex_array(None);
            let empty_vao = gl.create_vertex_array().unwrap();

            gl.use_program(Some(lighting));
            for (unit, (name, t)) in [
                ("g_base_color_metal", base_color),
                ("g_normal_oct", normal),
                ("g_material", material),
                ("g_depth", depth),
            ]
            .into_iter()
            .enumerate()
            {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                let loc = gl.get_uniform_location(lighting, name);
                gl.uniform_1_i32(loc.as_ref(), unit as i32);
            }
            gl.active_texture(glow::TEXTURE0);
            let view_projection = scene::projection(width, height) * scene::view();
            let loc = gl.get_uniform_location(lighting, "u_inverse_view_projection");
            gl.uniform_matrix_4_f32_slice(
                loc.as_ref(),
                false,
                &view_projection.inverse().to_cols_array(),
            );
            let loc = gl.get_uniform_location(lighting, "u_camera");
            gl.uniform_3_f32(loc.as_ref(), scene::EYE.x, scene::EYE.y, scene::EYE.z);
            let loc = gl.get_uniform_location(lighting, "u_size");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            let loc = gl.get_uniform_location(lighting, "u_roughness[0]");
            gl.uniform_1_f32_slice(loc.as_ref(), &[1.0, 0.35, 0.7, 0.3]);
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let loc = gl.get_uniform_location(lighting, &format!("u_light_position[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(lighting, &format!("u_light_color[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(None);
            // Global state, once.
            gl.enable(glow::FRAMEBUFFER_SRGB);
            gl.enable(glow::CULL_FACE);
            gl.cull_face(glow::BACK);
            gl.front_face(glow::CCW);
            PbrEngine {
                width: w,
                height: h,
                gbuffer,
                base_color,
                normal,
                material,
                depth,
                screen,
                screen_color,
                model,
                lighting,
                vao,
                vbo,
                count: (data.len() / 10) as i32,
                empty_vao,
            }
        }
    }

    fn gbuffer(&self) -> glow::Framebuffer {
        self.gbuffer
    }

    fn screen(&self) -> glow::Framebuffer {
        self.screen
    }

    fn units(&self) -> u32 {
        4
    }

    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, self.width, self.height);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 0.0]);
            gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0, 0.0, 0.0, 0.0]);
            gl.clear_buffer_u32_slice(glow::COLOR, 2, &[0, 0, 0, 0]);
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
            gl.use_program(Some(self.model));
            let vp = scene::projection(self.width as u32, self.height as u32) * scene::view();
            let loc = gl.get_uniform_location(self.model, "u_view_projection");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &vp.to_cols_array());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.count);
        }
    }

    fn lighting_pass(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.screen));
            gl.viewport(0, 0, self.width, self.height);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.use_program(Some(self.lighting));
            gl.bind_vertex_array(Some(self.empty_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn read_gbuffer(&self, gl: &glow::Context) -> Vec<Plane> {
        let (w, h) = (self.width as u32, self.height as u32);
        let read = |t, name, format, channels, channel, check| {
            harness::read_texture(
                gl,
                t,
                w,
                h,
                Read {
                    name,
                    format,
                    channels,
                    channel,
                    check,
                },
            )
        };
        vec![
            read(
                self.base_color,
                "base colour GL_COLOR_ATTACHMENT0 (GL_SRGB8_ALPHA8)",
                glow::RGBA,
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            read(
                self.normal,
                "octahedral normal GL_COLOR_ATTACHMENT1 (GL_RG16_SNORM)",
                glow::RG,
                2,
                Channel::Snorm16,
                Check::Constant,
            ),
            read(
                self.material,
                "material id GL_COLOR_ATTACHMENT2 (GL_R8UI)",
                glow::RED_INTEGER,
                1,
                Channel::U8,
                Check::Constant,
            ),
            read(
                self.depth,
                "depth GL_DEPTH_ATTACHMENT (GL_DEPTH_COMPONENT32F)",
                glow::DEPTH_COMPONENT,
                1,
                Channel::F32,
                Check::Smooth,
            ),
        ]
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::CULL_FACE);
            gl.delete_framebuffer(self.gbuffer);
            gl.delete_framebuffer(self.screen);
            for t in [
                self.base_color,
                self.normal,
                self.material,
                self.depth,
                self.screen_color,
            ] {
                gl.delete_texture(t);
            }
            gl.delete_program(self.model);
            gl.delete_program(self.lighting);
            gl.delete_vertex_array(self.vao);
            gl.delete_vertex_array(self.empty_vao);
            gl.delete_buffer(self.vbo);
        }
    }
}

/// The host run through the harness, with the options it needs: its
/// octahedral normals are selected from the reference sample, since a
/// blend of two octahedral encodings is not the encoding of a blended normal.
pub fn outcome(ctx: &deferred_msaa_lab::context::HeadlessContext, layers: u32) -> harness::Outcome {
    let options = RetrofitOptions {
        rules: vec![(ColorAttachment(1), ResolveRule::Select)],
        ..RetrofitOptions::default()
    };
    let options = harness::with_layers(
        options,
        layers,
        NormalAttachment {
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Octahedral,
        },
    );
    harness::run::<PbrEngine>(
        ctx,
        &harness::name("pbr", layers),
        &options,
        PbrEngine::frame,
    )
}

#[test]
fn a_pbr_engine_with_srgb_snorm_and_integer_attachments() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}
