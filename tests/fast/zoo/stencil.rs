//! A stencil-marking engine: the geometry pass writes stencil `1` wherever
//! geometry is (`glStencilFunc(GL_ALWAYS, 1, 0xFF)`, `glStencilOp(GL_KEEP,
//! GL_KEEP, GL_REPLACE)`), and the lighting pass runs its full-screen light
//! shader only where `stencil == 1` and draws the sky where `stencil != 1`,
//! the classic way deferred engines keep the lighting off empty pixels.
//!
//! The depth-stencil is one `GL_DEPTH24_STENCIL8` texture at
//! `GL_DEPTH_STENCIL_ATTACHMENT`, shared by the G-buffer FBO and the
//! lighting FBO (which tests against it with depth and stencil writes
//! off). Albedo + specular `GL_RGBA8`, view-space normal `GL_RGBA16F`,
//! view-space position `GL_RGBA32F` (the lighting does not sample depth,
//! which is attached to the framebuffer it draws into). The engine leaves
//! its geometry state (stencil test on, `GL_LEQUAL`) when it is done.

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::{NormalEncoding, StencilCopy};
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 150
in vec3 in_position;
in vec3 in_normal;
in vec4 in_albedo_spec;
uniform mat4 view_matrix;
uniform mat4 projection_matrix;
out vec3 view_position;
flat out vec3 view_normal;
flat out vec4 albedo_spec;
void main() {
    vec4 p = view_matrix * vec4(in_position, 1.0);
    view_position = p.xyz;
    view_normal = mat3(view_matrix) * in_normal;
    albedo_spec = in_albedo_spec;
    gl_Position = projection_matrix * p;
}
"#;

const MODEL_FS: &str = r#"#version 150
in vec3 view_position;
flat in vec3 view_normal;
flat in vec4 albedo_spec;
out vec4 out_albedo_spec;
out vec4 out_normal;
out vec4 out_position;
void main() {
    out_albedo_spec = albedo_spec;
    out_normal = vec4(normalize(view_normal), 0.0);
    out_position = vec4(view_position, 1.0);
}
"#;

const FULLSCREEN_VS: &str = r#"#version 150
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const LIGHT_FS: &str = r#"#version 150
uniform sampler2D albedo_spec_map;
uniform sampler2D normal_map;
uniform sampler2D position_map;
uniform vec3 light_position[2];   // view space
uniform vec3 light_color[2];
out vec4 frag_color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 albedo_spec = texelFetch(albedo_spec_map, p, 0);
    vec3 n = texelFetch(normal_map, p, 0).xyz;
    vec3 pos = texelFetch(position_map, p, 0).xyz;
    vec3 v = normalize(-pos);
    vec3 c = albedo_spec.rgb * 0.2;
    for (int i = 0; i < 2; ++i) {
        vec3 l = light_position[i] - pos;
        float d2 = dot(l, l);
        l = normalize(l);
        vec3 h = normalize(l + v);
        float diffuse = max(dot(n, l), 0.0);
        float specular = pow(max(dot(n, h), 0.0), 32.0) * albedo_spec.a;
        c += (albedo_spec.rgb * diffuse + specular) * light_color[i] * 4.0 / (1.0 + d2);
    }
    frag_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"#;

const SKY_FS: &str = r#"#version 150
uniform vec2 viewport_size;
out vec4 frag_color;
void main() {
    float t = gl_FragCoord.y / viewport_size.y;
    frag_color = vec4(mix(vec3(0.85, 0.8, 0.7), vec3(0.3, 0.45, 0.85), t), 1.0);
}
"#;

/// The stencil-marking engine.
pub struct StencilEngine {
    width: i32,
    height: i32,
    gbuffer: glow::Framebuffer,
    albedo_spec: glow::Texture,
    normal: glow::Texture,
    position: glow::Texture,
    depth_stencil: glow::Texture,
    light_fbo: glow::Framebuffer,
    light_color: glow::Texture,
    model: glow::Program,
    light: glow::Program,
    sky: glow::Program,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    count: i32,
    empty_vao: glow::VertexArray,
}

impl StencilEngine {
    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(scene::projection(self.width as u32, self.height as u32).to_cols_array())
    }
}

impl ZooHost for StencilEngine {
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
            let albedo_spec = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let normal = texture(glow::RGBA16F, glow::RGBA, glow::HALF_FLOAT);
            let position = texture(glow::RGBA32F, glow::RGBA, glow::FLOAT);
            let depth_stencil = texture(
                glow::DEPTH24_STENCIL8,
                glow::DEPTH_STENCIL,
                glow::UNSIGNED_INT_24_8,
            );
            let light_color = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let gbuffer = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(gbuffer));
            for (point, t) in [
                (glow::COLOR_ATTACHMENT0, albedo_spec),
                (glow::COLOR_ATTACHMENT1, normal),
                (glow::COLOR_ATTACHMENT2, position),
                (glow::DEPTH_STENCIL_ATTACHMENT, depth_stencil),
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
            let light_fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(light_fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(light_color),
                0,
            );
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(depth_stencil),
                0,
            );
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);

            // A GL 3.2 engine: GLSL 1.50, locations bound before linking.
            let model = harness::program_with_locations(
                gl,
                "stencil model",
                MODEL_VS,
                MODEL_FS,
                &[(0, "in_position"), (1, "in_normal"), (2, "in_albedo_spec")],
                &[
                    (0, "out_albedo_spec"),
                    (1, "out_normal"),
                    (2, "out_position"),
                ],
            );
            let light = harness::program(gl, "stencil light", FULLSCREEN_VS, LIGHT_FS);
            let sky = harness::program(gl, "stencil sky", FULLSCREEN_VS, SKY_FS);
            let mut data: Vec<f32> = Vec::new();
            for f in scene::faces() {
                for c in f.corners {
                    data.extend_from_slice(&c.to_array());
                    data.extend_from_slice(&f.normal.to_array());
                    data.extend_from_slice(&f.colour.to_array());
                    data.push(0.3 * f.material as f32);
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
            for (loc, size, offset) in [(0, 3, 0), (1, 3, 12), (2, 4, 24)] {
                gl.enable_vertex_attrib_array(loc);
                gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, 40, offset);
            }
            gl.bind_vertex_array(None);
            let empty_vao = gl.create_vertex_array().unwrap();

            gl.use_program(Some(light));
            for (unit, (name, t)) in [
                ("albedo_spec_map", albedo_spec),
                ("normal_map", normal),
                ("position_map", position),
            ]
            .into_iter()
            .enumerate()
            {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                let loc = gl.get_uniform_location(light, name);
                gl.uniform_1_i32(loc.as_ref(), unit as i32);
            }
            gl.active_texture(glow::TEXTURE0);
            let view = scene::view();
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let p = view.transform_point3(*p);
                let loc = gl.get_uniform_location(light, &format!("light_position[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(light, &format!("light_color[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(Some(sky));
            let loc = gl.get_uniform_location(sky, "viewport_size");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            gl.use_program(None);
            StencilEngine {
                width: w,
                height: h,
                gbuffer,
                albedo_spec,
                normal,
                position,
                depth_stencil,
                light_fbo,
                light_color,
                model,
                light,
                sky,
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
        self.light_fbo
    }

    fn units(&self) -> u32 {
        3
    }

    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, self.width, self.height);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear_stencil(0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LEQUAL);
            // Mark geometry in the stencil.
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::ALWAYS, 1, 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
            gl.use_program(Some(self.model));
            let view = scene::view();
            let projection = scene::projection(self.width as u32, self.height as u32);
            let loc = gl.get_uniform_location(self.model, "view_matrix");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &view.to_cols_array());
            let loc = gl.get_uniform_location(self.model, "projection_matrix");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &projection.to_cols_array());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.count);
        }
    }

    fn lighting_pass(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.light_fbo));
            gl.viewport(0, 0, self.width, self.height);
            gl.clear_color(1.0, 0.0, 1.0, 1.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            gl.disable(glow::DEPTH_TEST);
            gl.depth_mask(false);
            gl.disable(glow::BLEND);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_mask(0x00);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
            gl.bind_vertex_array(Some(self.empty_vao));
            // Light where geometry is...
            gl.stencil_func(glow::EQUAL, 1, 0xFF);
            gl.use_program(Some(self.light));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            // ... and the sky elsewhere.
            gl.stencil_func(glow::NOTEQUAL, 1, 0xFF);
            gl.use_program(Some(self.sky));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            gl.disable(glow::STENCIL_TEST);
            gl.stencil_mask(0xFF);
            gl.depth_mask(true);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn read_gbuffer(&self, gl: &glow::Context) -> Vec<Plane> {
        let (w, h) = (self.width as u32, self.height as u32);
        let texture = |t, name, channels, channel, check| {
            harness::read_texture(
                gl,
                t,
                w,
                h,
                Read {
                    name,
                    format: glow::RGBA,
                    channels,
                    channel,
                    check,
                },
            )
        };
        let depth_stencil = |name, format, channel, check| {
            harness::read_framebuffer(
                gl,
                self.gbuffer,
                None,
                w,
                h,
                Read {
                    name,
                    format,
                    channels: 1,
                    channel,
                    check,
                },
            )
        };
        vec![
            texture(
                self.albedo_spec,
                "albedo+specular GL_COLOR_ATTACHMENT0 (GL_RGBA8)",
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            texture(
                self.normal,
                "normal GL_COLOR_ATTACHMENT1 (GL_RGBA16F)",
                4,
                Channel::F16,
                Check::Constant,
            ),
            texture(
                self.position,
                "position GL_COLOR_ATTACHMENT2 (GL_RGBA32F)",
                4,
                Channel::F32,
                Check::Smooth,
            ),
            depth_stencil(
                "depth of GL_DEPTH_STENCIL_ATTACHMENT (GL_DEPTH24_STENCIL8)",
                glow::DEPTH_COMPONENT,
                Channel::F32,
                Check::Smooth,
            ),
            depth_stencil(
                "stencil of GL_DEPTH_STENCIL_ATTACHMENT (GL_DEPTH24_STENCIL8)",
                glow::STENCIL_INDEX,
                Channel::U8,
                Check::Constant,
            ),
        ]
    }

    fn needs_gl() -> (u32, u32) {
        (3, 2)
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.gbuffer);
            gl.delete_framebuffer(self.light_fbo);
            for t in [
                self.albedo_spec,
                self.normal,
                self.position,
                self.depth_stencil,
                self.light_color,
            ] {
                gl.delete_texture(t);
            }
            for p in [self.model, self.light, self.sky] {
                gl.delete_program(p);
            }
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
    harness::run::<StencilEngine>(
        ctx,
        &harness::name("stencil", layers),
        &options,
        StencilEngine::frame,
    )
}

#[test]
fn a_stencil_marking_engine_keeps_its_stencil_through_the_resolve() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}

/// The same engine where the driver cannot export stencil from a shader:
/// eight one-bit passes write the same values.
#[test]
fn the_stencil_comes_back_the_same_in_one_bit_passes() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    let options = RetrofitOptions {
        stencil: StencilCopy::BitPasses,
        ..RetrofitOptions::default()
    };
    harness::run::<StencilEngine>(&ctx, "stencil-bit-passes", &options, StencilEngine::frame)
        .assert_ok();
}

/// Without stencil texturing the stencil is blitted: the driver's sample,
/// which inside faces is every sample's value.
#[test]
fn a_blitted_stencil_holds_inside_faces() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    let options = RetrofitOptions {
        stencil: StencilCopy::Blit,
        ..RetrofitOptions::default()
    };
    harness::run::<StencilEngine>(&ctx, "stencil-blit", &options, StencilEngine::frame).assert_ok();
}
