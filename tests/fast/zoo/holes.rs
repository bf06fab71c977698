//! A host with a `GL_NONE` hole in its draw buffers: the G-buffer FBO keeps
//! an attachment for a buffer some other pass owns (engines do this with a
//! velocity buffer only their TAA path writes, or a decal or occlusion
//! buffer filled outside the geometry pass), so its geometry pass draws
//! through `glDrawBuffers({GL_COLOR_ATTACHMENT0, GL_NONE,
//! GL_COLOR_ATTACHMENT2})` and never touches attachment 1.
//!
//! Here attachment 1 is an `GL_R8` occlusion term the host bakes once at
//! start-up (a fixed pattern uploaded with `glTexImage2D`), read by the
//! lighting; albedo is `GL_RGBA8`, the view-space normal `GL_RGB10_A2`
//! (`n * 0.5 + 0.5`), depth a `GL_DEPTH_COMPONENT24` texture from which the
//! lighting reconstructs the view-space position with the inverse
//! projection. After the geometry pass the engine sets its viewport back
//! to the window's, which is larger than the G-buffer.

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 a_position;
layout (location = 1) in vec3 a_normal;
layout (location = 2) in vec3 a_albedo;
uniform mat4 u_view;
uniform mat4 u_projection;
flat out vec3 v_normal;
flat out vec3 v_albedo;
void main() {
    v_normal = mat3(u_view) * a_normal;
    v_albedo = a_albedo;
    gl_Position = u_projection * u_view * vec4(a_position, 1.0);
}
"#;

const MODEL_FS: &str = r#"#version 330 core
flat in vec3 v_normal;
flat in vec3 v_albedo;
layout (location = 0) out vec4 o_albedo;
layout (location = 2) out vec4 o_normal;
void main() {
    o_albedo = vec4(v_albedo, 1.0);
    o_normal = vec4(normalize(v_normal) * 0.5 + 0.5, 1.0);
}
"#;

const FULLSCREEN_VS: &str = r#"#version 330 core
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const LIGHTING_FS: &str = r#"#version 330 core
uniform sampler2D u_albedo;
uniform sampler2D u_occlusion;
uniform sampler2D u_normal;
uniform sampler2D u_depth;
uniform mat4 u_inverse_projection;
uniform vec2 u_size;
uniform vec3 u_light_position[2];   // view space
uniform vec3 u_light_color[2];
out vec4 o_color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(u_depth, p, 0).r;
    if (depth == 1.0) {
        o_color = vec4(0.55, 0.7, 0.95, 1.0);
        return;
    }
    vec4 ndc = vec4(gl_FragCoord.xy / u_size * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec4 view = u_inverse_projection * ndc;
    vec3 pos = view.xyz / view.w;
    vec3 albedo = texelFetch(u_albedo, p, 0).rgb;
    vec3 n = normalize(texelFetch(u_normal, p, 0).xyz * 2.0 - 1.0);
    float occlusion = texelFetch(u_occlusion, p, 0).r;
    vec3 c = albedo * 0.25 * occlusion;
    for (int i = 0; i < 2; ++i) {
        vec3 l = u_light_position[i] - pos;
        float d = length(l);
        c += albedo * u_light_color[i] * max(dot(n, l / d), 0.0) * 3.0 / (1.0 + d * d);
    }
    o_color = vec4(pow(c / (1.0 + c), vec3(1.0 / 2.2)), 1.0);
}
"#;

/// The engine with a hole in its draw buffers.
pub struct Holes {
    width: i32,
    height: i32,
    fbo: glow::Framebuffer,
    albedo: glow::Texture,
    occlusion: glow::Texture,
    normal: glow::Texture,
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

impl Holes {
    /// The projection for this size.
    pub fn projection(&self) -> glam::Mat4 {
        scene::projection(self.width as u32, self.height as u32)
    }

    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(self.projection().to_cols_array())
    }

    /// The baked occlusion: a fixed pattern, 0.5..1.
    fn occlusion_pattern(w: i32, h: i32) -> Vec<u8> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                128 + ((x * 7 + y * 13) % 128) as u8
            })
            .collect()
    }
}

impl ZooHost for Holes {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            let texture = |internal: u32, format: u32, ty: u32, data: Option<&[u8]>| {
                let t = gl.create_texture().unwrap();
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
                gl.tex_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    internal as i32,
                    w,
                    h,
                    0,
                    format,
                    ty,
                    glow::PixelUnpackData::Slice(data),
                );
                gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 4);
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
            let albedo = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE, None);
            let pattern = Self::occlusion_pattern(w, h);
            let occlusion = texture(glow::R8, glow::RED, glow::UNSIGNED_BYTE, Some(&pattern));
            let normal = texture(glow::RGB10_A2, glow::RGBA, glow::UNSIGNED_BYTE, None);
            let depth = texture(
                glow::DEPTH_COMPONENT24,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
                None,
            );
            let fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            for (point, t) in [
                (glow::COLOR_ATTACHMENT0, albedo),
                (glow::COLOR_ATTACHMENT1, occlusion),
                (glow::COLOR_ATTACHMENT2, normal),
                (glow::DEPTH_ATTACHMENT, depth),
            ] {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(t), 0);
            }
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0, glow::NONE, glow::COLOR_ATTACHMENT2]);
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            let screen_color = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE, None);
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

            let model = harness::program(gl, "holes model", MODEL_VS, MODEL_FS);
            let lighting = harness::program(gl, "holes lighting", FULLSCREEN_VS, LIGHTING_FS);
            let mut data: Vec<f32> = Vec::new();
            for f in scene::faces() {
                for c in f.corners {
                    data.extend_from_slice(&c.to_array());
                    data.extend_from_slice(&f.normal.to_array());
                    data.extend_from_slice(&f.colour.to_array());
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
            for (loc, offset) in [(0, 0), (1, 12), (2, 24)] {
                gl.enable_vertex_attrib_array(loc);
                gl.vertex_attrib_pointer_f32(loc, 3, glow::FLOAT, false, 36, offset);
            }
            gl.bind_vertex_array(None);
            let empty_vao = gl.create_vertex_array().unwrap();

            // Lighting inputs, bound once.
            gl.use_program(Some(lighting));
            for (unit, (name, t)) in [
                ("u_albedo", albedo),
                ("u_occlusion", occlusion),
                ("u_normal", normal),
                ("u_depth", depth),
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
            let projection = scene::projection(width, height);
            let view = scene::view();
            let loc = gl.get_uniform_location(lighting, "u_inverse_projection");
            gl.uniform_matrix_4_f32_slice(
                loc.as_ref(),
                false,
                &projection.inverse().to_cols_array(),
            );
            let loc = gl.get_uniform_location(lighting, "u_size");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let p = view.transform_point3(*p);
                let loc = gl.get_uniform_location(lighting, &format!("u_light_position[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(lighting, &format!("u_light_color[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(None);
            Holes {
                width: w,
                height: h,
                fbo,
                albedo,
                occlusion,
                normal,
                depth,
                screen,
                screen_color,
                model,
                lighting,
                vao,
                vbo,
                count: (data.len() / 9) as i32,
                empty_vao,
            }
        }
    }

    fn gbuffer(&self) -> glow::Framebuffer {
        self.fbo
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
            gl.disable(glow::BLEND);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            gl.use_program(Some(self.model));
            let loc = gl.get_uniform_location(self.model, "u_view");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &scene::view().to_cols_array());
            let loc = gl.get_uniform_location(self.model, "u_projection");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &self.projection().to_cols_array());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.count);
            // Back to the window's viewport for whatever comes next.
            gl.viewport(0, 0, self.width * 2, self.height * 2);
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
                self.albedo,
                "albedo GL_COLOR_ATTACHMENT0 (GL_RGBA8)",
                glow::RGBA,
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            read(
                self.occlusion,
                "occlusion GL_COLOR_ATTACHMENT1 (GL_R8, not drawn: GL_NONE)",
                glow::RED,
                1,
                Channel::Unorm8,
                Check::Untouched,
            ),
            read(
                self.normal,
                "normal GL_COLOR_ATTACHMENT2 (GL_RGB10_A2)",
                glow::RGBA,
                4,
                Channel::F32,
                Check::Constant,
            ),
            read(
                self.depth,
                "depth GL_DEPTH_ATTACHMENT (GL_DEPTH_COMPONENT24)",
                glow::DEPTH_COMPONENT,
                1,
                Channel::F32,
                Check::Smooth,
            ),
        ]
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_framebuffer(self.screen);
            for t in [
                self.albedo,
                self.occlusion,
                self.normal,
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

/// The host run through the harness, with the options it needs.
pub fn outcome(ctx: &deferred_msaa_lab::context::HeadlessContext, layers: u32) -> harness::Outcome {
    let options = harness::with_layers(
        RetrofitOptions::default(),
        layers,
        NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Unorm,
        },
    );
    harness::run::<Holes>(ctx, &harness::name("holes", layers), &options, Holes::frame)
}

#[test]
fn a_hole_in_the_draw_buffers_leaves_the_attachment_behind_it_alone() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}
