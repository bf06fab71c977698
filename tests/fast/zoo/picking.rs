//! Renderbuffer colour attachments: an editor-style engine that keeps an
//! object-id picking buffer in its G-buffer, a `GL_R32UI` **renderbuffer**
//! at `GL_COLOR_ATTACHMENT2` that the geometry pass writes and the editor
//! reads back under the cursor with `glReadPixels(GL_RED_INTEGER,
//! GL_UNSIGNED_INT)`, beside the textures the lighting reads (albedo
//! `GL_RGBA8`, view-space normal `GL_RGBA16F`, depth
//! `GL_DEPTH_COMPONENT32F`, the view-space position reconstructed from it).

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 a_position;
layout (location = 1) in vec3 a_normal;
layout (location = 2) in vec3 a_albedo;
layout (location = 3) in float a_object;
uniform mat4 u_view;
uniform mat4 u_projection;
flat out vec3 v_normal;
flat out vec3 v_albedo;
flat out uint v_object;
void main() {
    v_normal = mat3(u_view) * a_normal;
    v_albedo = a_albedo;
    v_object = uint(a_object);
    gl_Position = u_projection * u_view * vec4(a_position, 1.0);
}
"#;

const MODEL_FS: &str = r#"#version 330 core
flat in vec3 v_normal;
flat in vec3 v_albedo;
flat in uint v_object;
layout (location = 0) out vec4 o_albedo;
layout (location = 1) out vec4 o_normal;
layout (location = 2) out uint o_object_id;
void main() {
    o_albedo = vec4(v_albedo, 1.0);
    o_normal = vec4(normalize(v_normal), 1.0);
    o_object_id = v_object;
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
        o_color = vec4(0.2, 0.2, 0.25, 1.0);
        return;
    }
    vec4 view = u_inverse_projection * vec4(gl_FragCoord.xy / u_size * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec3 pos = view.xyz / view.w;
    vec3 albedo = texelFetch(u_albedo, p, 0).rgb;
    vec3 n = normalize(texelFetch(u_normal, p, 0).xyz);
    vec3 c = albedo * 0.2;
    for (int i = 0; i < 2; ++i) {
        vec3 l = u_light_position[i] - pos;
        float d = length(l);
        c += albedo * u_light_color[i] * max(dot(n, l / d), 0.0) * 4.0 / (1.0 + d * d);
    }
    o_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"#;

/// The editor engine with a picking renderbuffer.
pub struct Picking {
    width: i32,
    height: i32,
    fbo: glow::Framebuffer,
    albedo: glow::Texture,
    normal: glow::Texture,
    object_id: glow::Renderbuffer,
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

impl Picking {
    fn projection(&self) -> glam::Mat4 {
        scene::projection(self.width as u32, self.height as u32)
    }

    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(self.projection().to_cols_array())
    }

    /// The editor's pick: the ids under a rectangle, as `glReadPixels` gives them.
    pub fn pick(&self, gl: &glow::Context, width: u32, height: u32) -> Plane {
        harness::read_framebuffer(
            gl,
            self.fbo,
            Some(glow::COLOR_ATTACHMENT2),
            width,
            height,
            Read {
                name: "object id GL_COLOR_ATTACHMENT2 (GL_R32UI renderbuffer)",
                format: glow::RED_INTEGER,
                channels: 1,
                channel: Channel::U32,
                check: Check::Constant,
            },
        )
    }
}

impl ZooHost for Picking {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            let texture = |internal: u32, format: u32, ty: u32| {
                let t = gl.create_texture().unwrap();
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.tex_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    internal as i32,
                    w,
                    h,
                    0,
                    format,
                    ty,
                    glow::PixelUnpackData::Slice(None),
                );
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
            let albedo = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let normal = texture(glow::RGBA16F, glow::RGBA, glow::HALF_FLOAT);
            let depth = texture(glow::DEPTH_COMPONENT32F, glow::DEPTH_COMPONENT, glow::FLOAT);
            let object_id = gl.create_renderbuffer().unwrap();
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(object_id));
            gl.renderbuffer_storage(glow::RENDERBUFFER, glow::R32UI, w, h);
            gl.bind_renderbuffer(glow::RENDERBUFFER, None);
            let fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            for (point, t) in [
                (glow::COLOR_ATTACHMENT0, albedo),
                (glow::COLOR_ATTACHMENT1, normal),
                (glow::DEPTH_ATTACHMENT, depth),
            ] {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(t), 0);
            }
            gl.framebuffer_renderbuffer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT2,
                glow::RENDERBUFFER,
                Some(object_id),
            );
            gl.draw_buffers(&[
                glow::COLOR_ATTACHMENT0,
                glow::COLOR_ATTACHMENT1,
                glow::COLOR_ATTACHMENT2,
            ]);
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            let screen_color = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
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

            let model = harness::program(gl, "picking model", MODEL_VS, MODEL_FS);
            let lighting = harness::program(gl, "picking lighting", FULLSCREEN_VS, LIGHTING_FS);
            let mut data: Vec<f32> = Vec::new();
            for f in scene::faces() {
                for c in f.corners {
                    data.extend_from_slice(&c.to_array());
                    data.extend_from_slice(&f.normal.to_array());
                    data.extend_from_slice(&f.colour.to_array());
                    data.push(1000.0 + f.object as f32);
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
                ("u_albedo", albedo),
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
            let loc = gl.get_uniform_location(lighting, "u_inverse_projection");
            gl.uniform_matrix_4_f32_slice(
                loc.as_ref(),
                false,
                &scene::projection(width, height).inverse().to_cols_array(),
            );
            let loc = gl.get_uniform_location(lighting, "u_size");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            let view = scene::view();
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let p = view.transform_point3(*p);
                let loc = gl.get_uniform_location(lighting, &format!("u_light_position[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(lighting, &format!("u_light_color[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(None);
            Picking {
                width: w,
                height: h,
                fbo,
                albedo,
                normal,
                object_id,
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
        self.fbo
    }

    fn screen(&self) -> glow::Framebuffer {
        self.screen
    }

    fn units(&self) -> u32 {
        3
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
            let loc = gl.get_uniform_location(self.model, "u_view");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &scene::view().to_cols_array());
            let loc = gl.get_uniform_location(self.model, "u_projection");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &self.projection().to_cols_array());
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
                self.albedo,
                "albedo GL_COLOR_ATTACHMENT0 (GL_RGBA8)",
                glow::RGBA,
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            read(
                self.normal,
                "normal GL_COLOR_ATTACHMENT1 (GL_RGBA16F)",
                glow::RGBA,
                4,
                Channel::F16,
                Check::Constant,
            ),
            self.pick(gl, w, h),
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
            gl.delete_framebuffer(self.fbo);
            gl.delete_framebuffer(self.screen);
            for t in [self.albedo, self.normal, self.depth, self.screen_color] {
                gl.delete_texture(t);
            }
            gl.delete_renderbuffer(self.object_id);
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
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Xyz,
        },
    );
    harness::run::<Picking>(
        ctx,
        &harness::name("picking", layers),
        &options,
        Picking::frame,
    )
}

#[test]
fn a_picking_renderbuffer_beside_the_lit_textures() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}
