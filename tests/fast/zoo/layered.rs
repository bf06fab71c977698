//! A layered array-texture G-buffer, the habit of Rust engines on glow that
//! keep their whole G-buffer in one `GL_TEXTURE_2D_ARRAY` (three-d's
//! deferred pipeline did, with its colour targets as layers of one array
//! texture): the colour layers are attached one each with
//! `glFramebufferTextureLayer` (layer 0 albedo at `GL_COLOR_ATTACHMENT0`,
//! layer 1 the view-space normal at `GL_COLOR_ATTACHMENT1`, both
//! `GL_RGBA8`, the normal as `n * 0.5 + 0.5`), depth is a plain
//! `GL_DEPTH_COMPONENT24` texture, and the lighting reads the layers
//! through one `sampler2DArray`. The engine keeps its scissor test on,
//! with the box over the whole target.

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 position;
layout (location = 1) in vec3 normal;
layout (location = 2) in vec3 color;
uniform mat4 viewProjection;
uniform mat4 view;
flat out vec3 nor;
flat out vec3 col;
void main() {
    nor = mat3(view) * normal;
    col = color;
    gl_Position = viewProjection * vec4(position, 1.0);
}
"#;

const MODEL_FS: &str = r#"#version 330 core
flat in vec3 nor;
flat in vec3 col;
layout (location = 0) out vec4 outColor;
layout (location = 1) out vec4 outNormal;
void main() {
    outColor = vec4(col, 1.0);
    outNormal = vec4(0.5 * normalize(nor) + 0.5, 1.0);
}
"#;

const FULLSCREEN_VS: &str = r#"#version 330 core
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const LIGHTING_FS: &str = r#"#version 330 core
uniform sampler2DArray gbuffer;
uniform sampler2D depthMap;
uniform mat4 viewProjectionInverse;
uniform mat4 view;
uniform vec2 screenSize;
uniform vec3 lightPosition[2];
uniform vec3 lightColor[2];
out vec4 outColor;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(depthMap, p, 0).r;
    if (depth == 1.0) {
        outColor = vec4(0.7, 0.8, 0.9, 1.0);
        return;
    }
    vec3 albedo = texelFetch(gbuffer, ivec3(p, 0), 0).rgb;
    vec3 n = normalize(texelFetch(gbuffer, ivec3(p, 1), 0).xyz * 2.0 - 1.0);
    n = normalize(transpose(mat3(view)) * n);
    vec4 w = viewProjectionInverse * vec4(gl_FragCoord.xy / screenSize * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec3 pos = w.xyz / w.w;
    vec3 c = albedo * 0.15;
    for (int i = 0; i < 2; ++i) {
        vec3 l = lightPosition[i] - pos;
        float d2 = dot(l, l);
        c += albedo * lightColor[i] * max(dot(n, normalize(l)), 0.0) * 5.0 / (1.0 + d2);
    }
    outColor = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"#;

/// The array-texture engine.
pub struct Layered {
    width: i32,
    height: i32,
    fbo: glow::Framebuffer,
    array: glow::Texture,
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

impl Layered {
    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(scene::projection(self.width as u32, self.height as u32).to_cols_array())
    }
}

impl ZooHost for Layered {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            let nearest = |target: u32| {
                gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
                gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
            };
            let array = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, Some(array));
            gl.tex_image_3d(
                glow::TEXTURE_2D_ARRAY,
                0,
                glow::RGBA8 as i32,
                w,
                h,
                2,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            nearest(glow::TEXTURE_2D_ARRAY);
            let depth = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D, Some(depth));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::DEPTH_COMPONENT24 as i32,
                w,
                h,
                0,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
                glow::PixelUnpackData::Slice(None),
            );
            nearest(glow::TEXTURE_2D);
            let fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_layer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                Some(array),
                0,
                0,
            );
            gl.framebuffer_texture_layer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT1,
                Some(array),
                0,
                1,
            );
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(depth),
                0,
            );
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0, glow::COLOR_ATTACHMENT1]);
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            let screen_color = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D, Some(screen_color));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                w,
                h,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
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
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, None);

            let model = harness::program(gl, "layered model", MODEL_VS, MODEL_FS);
            let lighting = harness::program(gl, "layered lighting", FULLSCREEN_VS, LIGHTING_FS);
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

            gl.use_program(Some(lighting));
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, Some(array));
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, Some(depth));
            gl.active_texture(glow::TEXTURE0);
            let int = |name: &str, v: i32| {
                let loc = gl.get_uniform_location(lighting, name);
                gl.uniform_1_i32(loc.as_ref(), v);
            };
            int("gbuffer", 0);
            int("depthMap", 1);
            let view = scene::view();
            let vp = scene::projection(width, height) * view;
            let loc = gl.get_uniform_location(lighting, "viewProjectionInverse");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &vp.inverse().to_cols_array());
            let loc = gl.get_uniform_location(lighting, "view");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &view.to_cols_array());
            let loc = gl.get_uniform_location(lighting, "screenSize");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let loc = gl.get_uniform_location(lighting, &format!("lightPosition[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(lighting, &format!("lightColor[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(None);
            Layered {
                width: w,
                height: h,
                fbo,
                array,
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
        2
    }

    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, self.width, self.height);
            gl.enable(glow::SCISSOR_TEST);
            gl.scissor(0, 0, self.width, self.height);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            gl.use_program(Some(self.model));
            let view = scene::view();
            let vp = scene::projection(self.width as u32, self.height as u32) * view;
            let loc = gl.get_uniform_location(self.model, "viewProjection");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &vp.to_cols_array());
            let loc = gl.get_uniform_location(self.model, "view");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &view.to_cols_array());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.count);
        }
    }

    fn lighting_pass(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.screen));
            gl.viewport(0, 0, self.width, self.height);
            gl.scissor(0, 0, self.width, self.height);
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
        let layer = |layer, name| {
            harness::read_texture_layers(
                gl,
                glow::TEXTURE_2D_ARRAY,
                self.array,
                w,
                h,
                2,
                layer,
                Read {
                    name,
                    format: glow::RGBA,
                    channels: 4,
                    channel: Channel::Unorm8,
                    check: Check::Constant,
                },
            )
        };
        vec![
            layer(
                0,
                "albedo GL_COLOR_ATTACHMENT0 (GL_RGBA8, layer 0 of a GL_TEXTURE_2D_ARRAY)",
            ),
            layer(
                1,
                "normal GL_COLOR_ATTACHMENT1 (GL_RGBA8, layer 1 of a GL_TEXTURE_2D_ARRAY)",
            ),
            harness::read_texture(
                gl,
                self.depth,
                w,
                h,
                Read {
                    name: "depth GL_DEPTH_ATTACHMENT (GL_DEPTH_COMPONENT24)",
                    format: glow::DEPTH_COMPONENT,
                    channels: 1,
                    channel: Channel::F32,
                    check: Check::Smooth,
                },
            ),
        ]
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.delete_framebuffer(self.fbo);
            gl.delete_framebuffer(self.screen);
            for t in [self.array, self.depth, self.screen_color] {
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
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Unorm,
        },
    );
    harness::run::<Layered>(
        ctx,
        &harness::name("layered", layers),
        &options,
        Layered::frame,
    )
}

#[test]
fn a_layered_array_texture_gbuffer_is_resolved_layer_by_layer() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}
