//! The tutorial layout: LearnOpenGL's "Deferred Shading" chapter, the most
//! copied deferred renderer there is, transcribed call for call.
//!
//! `gPosition` and `gNormal` are `glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F,
//! w, h, 0, GL_RGBA, GL_FLOAT, NULL)` with `GL_NEAREST` filtering; `gAlbedoSpec`
//! is created with the *unsized* internal format `GL_RGBA`
//! (`GL_UNSIGNED_BYTE`); depth is a `GL_DEPTH_COMPONENT` **renderbuffer**;
//! `glDrawBuffers` names the three attachments. The geometry shader writes
//! the **world-space** position and normal (`vec3` outputs), the diffuse
//! colour and a specular intensity in alpha; the lighting shader lights in
//! world space with a `viewPos` uniform, Blinn-Phong with the tutorial's
//! linear-quadratic attenuation, on a screen quad drawn with depth testing
//! left on. Then, as the chapter's "combining deferred with forward" part
//! does, the G-buffer's depth is blitted to the screen framebuffer and the
//! lights are drawn as small forward-shaded cubes against it.
//!
//! Departures, each for the zoo's sake: the diffuse colour and specular
//! intensity come from vertex attributes instead of the model's textures
//! (flat colours), the "screen" is an 8-bit framebuffer of the host's own
//! (the tests have no window), and the G-buffer textures are bound to their
//! units once, at start-up.

use super::harness::{self, Channel, Check, Plane, Read, W, ZooHost};
use super::scene;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, PositionSpace, RetrofitOptions};
use glow::HasContext;

const GBUFFER_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 aPos;
layout (location = 1) in vec3 aNormal;
layout (location = 2) in vec4 aDiffuseSpec;

out vec3 FragPos;
out vec3 Normal;
flat out vec4 DiffuseSpec; // the model's (one-colour) diffuse and specular maps

uniform mat4 model;
uniform mat4 view;
uniform mat4 projection;

void main()
{
    vec4 worldPos = model * vec4(aPos, 1.0);
    FragPos = worldPos.xyz;
    DiffuseSpec = aDiffuseSpec;

    mat3 normalMatrix = transpose(inverse(mat3(model)));
    Normal = normalMatrix * aNormal;

    gl_Position = projection * view * worldPos;
}
"#;

const GBUFFER_FS: &str = r#"#version 330 core
layout (location = 0) out vec3 gPosition;
layout (location = 1) out vec3 gNormal;
layout (location = 2) out vec4 gAlbedoSpec;

in vec3 FragPos;
in vec3 Normal;
flat in vec4 DiffuseSpec;

void main()
{
    // store the fragment position vector in the first gbuffer texture
    gPosition = FragPos;
    // also store the per-fragment normals into the gbuffer
    gNormal = normalize(Normal);
    // and the diffuse per-fragment color
    gAlbedoSpec.rgb = DiffuseSpec.rgb;
    // store specular intensity in gAlbedoSpec's alpha component
    gAlbedoSpec.a = DiffuseSpec.a;
}
"#;

const DEFERRED_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 aPos;
layout (location = 1) in vec2 aTexCoords;

out vec2 TexCoords;

void main()
{
    TexCoords = aTexCoords;
    gl_Position = vec4(aPos, 1.0);
}
"#;

const DEFERRED_FS: &str = r#"#version 330 core
out vec4 FragColor;

in vec2 TexCoords;

uniform sampler2D gPosition;
uniform sampler2D gNormal;
uniform sampler2D gAlbedoSpec;

struct Light {
    vec3 Position;
    vec3 Color;

    float Linear;
    float Quadratic;
};
const int NR_LIGHTS = 2;
uniform Light lights[NR_LIGHTS];
uniform vec3 viewPos;

void main()
{
    // retrieve data from gbuffer
    vec3 FragPos = texture(gPosition, TexCoords).rgb;
    vec3 Normal = texture(gNormal, TexCoords).rgb;
    vec3 Diffuse = texture(gAlbedoSpec, TexCoords).rgb;
    float Specular = texture(gAlbedoSpec, TexCoords).a;

    // then calculate lighting as usual
    vec3 lighting  = Diffuse * 0.1; // hard-coded ambient component
    vec3 viewDir  = normalize(viewPos - FragPos);
    for(int i = 0; i < NR_LIGHTS; ++i)
    {
        // diffuse
        vec3 lightDir = normalize(lights[i].Position - FragPos);
        vec3 diffuse = max(dot(Normal, lightDir), 0.0) * Diffuse * lights[i].Color;
        // specular
        vec3 halfwayDir = normalize(lightDir + viewDir);
        float spec = pow(max(dot(Normal, halfwayDir), 0.0), 16.0);
        vec3 specular = lights[i].Color * spec * Specular;
        // attenuation
        float distance = length(lights[i].Position - FragPos);
        float attenuation = 1.0 / (1.0 + lights[i].Linear * distance + lights[i].Quadratic * distance * distance);
        diffuse *= attenuation;
        specular *= attenuation;
        lighting += diffuse + specular;
    }
    FragColor = vec4(lighting, 1.0);
}
"#;

const LIGHT_BOX_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 aPos;

uniform mat4 projection;
uniform mat4 view;
uniform mat4 model;

void main()
{
    gl_Position = projection * view * model * vec4(aPos, 1.0);
}
"#;

const LIGHT_BOX_FS: &str = r#"#version 330 core
layout (location = 0) out vec4 FragColor;

uniform vec3 lightColor;

void main()
{
    FragColor = vec4(lightColor, 1.0);
}
"#;

/// The tutorial's host.
pub struct LearnOpenGl {
    width: i32,
    height: i32,
    g_buffer: glow::Framebuffer,
    g_position: glow::Texture,
    g_normal: glow::Texture,
    g_albedo_spec: glow::Texture,
    rbo_depth: glow::Renderbuffer,
    screen: glow::Framebuffer,
    screen_color: glow::Renderbuffer,
    screen_depth: glow::Renderbuffer,
    shader_geometry_pass: glow::Program,
    shader_lighting_pass: glow::Program,
    shader_light_box: glow::Program,
    scene_vao: glow::VertexArray,
    scene_vbo: glow::Buffer,
    scene_vertices: i32,
    quad_vao: glow::VertexArray,
    quad_vbo: glow::Buffer,
    cube_vao: glow::VertexArray,
    cube_vbo: glow::Buffer,
}

unsafe fn set_mat4(gl: &glow::Context, program: glow::Program, name: &str, m: &glam::Mat4) {
    unsafe {
        let loc = gl.get_uniform_location(program, name);
        gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &m.to_cols_array());
    }
}

unsafe fn set_vec3(gl: &glow::Context, program: glow::Program, name: &str, v: glam::Vec3) {
    unsafe {
        let loc = gl.get_uniform_location(program, name);
        gl.uniform_3_f32(loc.as_ref(), v.x, v.y, v.z);
    }
}

unsafe fn set_float(gl: &glow::Context, program: glow::Program, name: &str, v: f32) {
    unsafe {
        let loc = gl.get_uniform_location(program, name);
        gl.uniform_1_f32(loc.as_ref(), v);
    }
}

unsafe fn set_int(gl: &glow::Context, program: glow::Program, name: &str, v: i32) {
    unsafe {
        let loc = gl.get_uniform_location(program, name);
        gl.uniform_1_i32(loc.as_ref(), v);
    }
}

impl LearnOpenGl {
    /// The projection, as the tutorial builds it with glm::perspective.
    pub fn projection(&self) -> glam::Mat4 {
        scene::projection(self.width as u32, self.height as u32)
    }

    /// What the host passes with the default depth key: the projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(self.projection().to_cols_array())
    }

    /// With the world-space position as the key: the projection and the view.
    pub fn frame_with_view(&self) -> Frame {
        self.frame().with_view(scene::view().to_cols_array())
    }
}

impl ZooHost for LearnOpenGl {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            // configure g-buffer framebuffer
            let g_buffer = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(g_buffer));
            let color_buffer = |internal: u32, ty: u32, attachment: u32| {
                let t = gl.create_texture().unwrap();
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.tex_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    internal as i32,
                    w,
                    h,
                    0,
                    glow::RGBA,
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
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    attachment,
                    glow::TEXTURE_2D,
                    Some(t),
                    0,
                );
                t
            };
            // position color buffer
            let g_position = color_buffer(glow::RGBA16F, glow::FLOAT, glow::COLOR_ATTACHMENT0);
            // normal color buffer
            let g_normal = color_buffer(glow::RGBA16F, glow::FLOAT, glow::COLOR_ATTACHMENT1);
            // color + specular color buffer
            let g_albedo_spec =
                color_buffer(glow::RGBA, glow::UNSIGNED_BYTE, glow::COLOR_ATTACHMENT2);
            // tell OpenGL which color attachments we'll use (of this framebuffer) for rendering
            gl.draw_buffers(&[
                glow::COLOR_ATTACHMENT0,
                glow::COLOR_ATTACHMENT1,
                glow::COLOR_ATTACHMENT2,
            ]);
            // create and attach depth buffer (renderbuffer)
            let rbo_depth = gl.create_renderbuffer().unwrap();
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rbo_depth));
            gl.renderbuffer_storage(glow::RENDERBUFFER, glow::DEPTH_COMPONENT, w, h);
            gl.framebuffer_renderbuffer(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::RENDERBUFFER,
                Some(rbo_depth),
            );
            // finally check if framebuffer is complete
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE,
                "Framebuffer not complete!"
            );

            // The "default framebuffer": colour and the same depth format.
            let screen = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(screen));
            let screen_color = gl.create_renderbuffer().unwrap();
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(screen_color));
            gl.renderbuffer_storage(glow::RENDERBUFFER, glow::RGBA8, w, h);
            gl.framebuffer_renderbuffer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::RENDERBUFFER,
                Some(screen_color),
            );
            let screen_depth = gl.create_renderbuffer().unwrap();
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(screen_depth));
            gl.renderbuffer_storage(glow::RENDERBUFFER, glow::DEPTH_COMPONENT, w, h);
            gl.framebuffer_renderbuffer(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::RENDERBUFFER,
                Some(screen_depth),
            );
            assert_eq!(
                gl.check_framebuffer_status(glow::FRAMEBUFFER),
                glow::FRAMEBUFFER_COMPLETE
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.bind_renderbuffer(glow::RENDERBUFFER, None);

            let shader_geometry_pass = harness::program(gl, "g_buffer", GBUFFER_VS, GBUFFER_FS);
            let shader_lighting_pass =
                harness::program(gl, "deferred_shading", DEFERRED_VS, DEFERRED_FS);
            let shader_light_box =
                harness::program(gl, "deferred_light_box", LIGHT_BOX_VS, LIGHT_BOX_FS);

            // The scene: position, normal, diffuse + specular per vertex.
            let mut data: Vec<f32> = Vec::new();
            for f in scene::faces() {
                for c in f.corners {
                    data.extend_from_slice(&c.to_array());
                    data.extend_from_slice(&f.normal.to_array());
                    data.extend_from_slice(&f.colour.to_array());
                    data.push(0.25 * f.material as f32);
                }
            }
            let scene_vao = gl.create_vertex_array().unwrap();
            let scene_vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(scene_vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(scene_vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&data),
                glow::STATIC_DRAW,
            );
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 40, 0);
            gl.enable_vertex_attrib_array(1);
            gl.vertex_attrib_pointer_f32(1, 3, glow::FLOAT, false, 40, 12);
            gl.enable_vertex_attrib_array(2);
            gl.vertex_attrib_pointer_f32(2, 4, glow::FLOAT, false, 40, 24);

            // renderQuad()
            #[rustfmt::skip]
            let quad: [f32; 20] = [
                // positions        // texture Coords
                -1.0,  1.0, 0.0, 0.0, 1.0,
                -1.0, -1.0, 0.0, 0.0, 0.0,
                 1.0,  1.0, 0.0, 1.0, 1.0,
                 1.0, -1.0, 0.0, 1.0, 0.0,
            ];
            let quad_vao = gl.create_vertex_array().unwrap();
            let quad_vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(quad_vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(quad_vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&quad),
                glow::STATIC_DRAW,
            );
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 20, 0);
            gl.enable_vertex_attrib_array(1);
            gl.vertex_attrib_pointer_f32(1, 2, glow::FLOAT, false, 20, 12);

            // renderCube(): 36 vertices of a unit cube, -1..1.
            let mut cube: Vec<f32> = Vec::new();
            for axis in 0..3 {
                for sign in [-1.0f32, 1.0] {
                    let corner = |a: f32, b: f32| {
                        let mut p = [0.0f32; 3];
                        p[axis] = sign;
                        p[(axis + 1) % 3] = a;
                        p[(axis + 2) % 3] = b;
                        p
                    };
                    for (a, b) in [
                        (-1.0, -1.0),
                        (1.0, -1.0),
                        (1.0, 1.0),
                        (-1.0, -1.0),
                        (1.0, 1.0),
                        (-1.0, 1.0),
                    ] {
                        cube.extend_from_slice(&corner(a, b));
                    }
                }
            }
            let cube_vao = gl.create_vertex_array().unwrap();
            let cube_vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(cube_vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(cube_vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&cube),
                glow::STATIC_DRAW,
            );
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 12, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);

            // configure global opengl state
            gl.enable(glow::DEPTH_TEST);

            // shader configuration
            gl.use_program(Some(shader_lighting_pass));
            set_int(gl, shader_lighting_pass, "gPosition", 0);
            set_int(gl, shader_lighting_pass, "gNormal", 1);
            set_int(gl, shader_lighting_pass, "gAlbedoSpec", 2);
            for (i, (position, colour)) in scene::LIGHTS.iter().enumerate() {
                let name = |field: &str| format!("lights[{i}].{field}");
                set_vec3(gl, shader_lighting_pass, &name("Position"), *position);
                set_vec3(gl, shader_lighting_pass, &name("Color"), *colour * 1.6);
                // update attenuation parameters and calculate radius
                set_float(gl, shader_lighting_pass, &name("Linear"), 0.09);
                set_float(gl, shader_lighting_pass, &name("Quadratic"), 0.032);
            }
            set_vec3(gl, shader_lighting_pass, "viewPos", scene::EYE);
            // The G-buffer's units, bound once.
            for (unit, t) in [g_position, g_normal, g_albedo_spec]
                .into_iter()
                .enumerate()
            {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
            }
            gl.active_texture(glow::TEXTURE0);

            LearnOpenGl {
                width: w,
                height: h,
                g_buffer,
                g_position,
                g_normal,
                g_albedo_spec,
                rbo_depth,
                screen,
                screen_color,
                screen_depth,
                shader_geometry_pass,
                shader_lighting_pass,
                shader_light_box,
                scene_vao,
                scene_vbo,
                scene_vertices: (data.len() / 10) as i32,
                quad_vao,
                quad_vbo,
                cube_vao,
                cube_vbo,
            }
        }
    }

    fn gbuffer(&self) -> glow::Framebuffer {
        self.g_buffer
    }

    fn screen(&self) -> glow::Framebuffer {
        self.screen
    }

    fn units(&self) -> u32 {
        3
    }

    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        unsafe {
            // 1. geometry pass: render scene's geometry/color data into gbuffer
            gl.viewport(0, 0, self.width, self.height);
            gl.clear_color(0.0, 0.0, 0.0, 1.0);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            let s = self.shader_geometry_pass;
            gl.use_program(Some(s));
            set_mat4(gl, s, "projection", &self.projection());
            set_mat4(gl, s, "view", &scene::view());
            set_mat4(gl, s, "model", &glam::Mat4::IDENTITY);
            gl.bind_vertex_array(Some(self.scene_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.scene_vertices);
        }
    }

    fn lighting_pass(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.screen));
            gl.viewport(0, 0, self.width, self.height);
            gl.clear_color(0.0, 0.0, 0.0, 1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            // 2. lighting pass: calculate lighting by iterating over a screen filled quad
            // pixel-by-pixel using the gbuffer's content.
            gl.use_program(Some(self.shader_lighting_pass));
            // finally render quad
            gl.bind_vertex_array(Some(self.quad_vao));
            gl.draw_arrays(glow::TRIANGLE_STRIP, 0, 4);
            gl.bind_vertex_array(None);

            // 2.5. copy content of geometry's depth buffer to default framebuffer's depth buffer
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.g_buffer));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(self.screen));
            gl.blit_framebuffer(
                0,
                0,
                self.width,
                self.height,
                0,
                0,
                self.width,
                self.height,
                glow::DEPTH_BUFFER_BIT,
                glow::NEAREST,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.screen));

            // 3. render lights on top of scene
            let s = self.shader_light_box;
            gl.use_program(Some(s));
            set_mat4(gl, s, "projection", &self.projection());
            set_mat4(gl, s, "view", &scene::view());
            gl.bind_vertex_array(Some(self.cube_vao));
            for (position, colour) in scene::LIGHTS {
                let model = glam::Mat4::from_translation(position)
                    * glam::Mat4::from_scale(glam::Vec3::splat(0.125));
                set_mat4(gl, s, "model", &model);
                set_vec3(gl, s, "lightColor", colour);
                gl.draw_arrays(glow::TRIANGLES, 0, 36);
            }
            gl.bind_vertex_array(None);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn read_gbuffer(&self, gl: &glow::Context) -> Vec<Plane> {
        let (w, h) = (self.width as u32, self.height as u32);
        let rgb16f = |name, texture, check| {
            harness::read_texture(
                gl,
                texture,
                w,
                h,
                Read {
                    name,
                    format: glow::RGB,
                    channels: 3,
                    channel: Channel::F16,
                    check,
                },
            )
        };
        vec![
            rgb16f(
                "gPosition GL_COLOR_ATTACHMENT0 (GL_RGBA16F)",
                self.g_position,
                Check::Smooth,
            ),
            // The tutorial interpolates its normal (`normalize(Normal)`):
            // equal at the corners, it may still vary by an ulp over a face.
            rgb16f(
                "gNormal GL_COLOR_ATTACHMENT1 (GL_RGBA16F)",
                self.g_normal,
                Check::Smooth,
            ),
            harness::read_texture(
                gl,
                self.g_albedo_spec,
                w,
                h,
                Read {
                    name: "gAlbedoSpec GL_COLOR_ATTACHMENT2 (GL_RGBA)",
                    format: glow::RGBA,
                    channels: 4,
                    channel: Channel::Unorm8,
                    check: Check::Constant,
                },
            ),
            harness::read_framebuffer(
                gl,
                self.g_buffer,
                None,
                w,
                h,
                Read {
                    name: "rboDepth GL_DEPTH_ATTACHMENT (GL_DEPTH_COMPONENT renderbuffer)",
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
            gl.delete_framebuffer(self.g_buffer);
            gl.delete_framebuffer(self.screen);
            for t in [self.g_position, self.g_normal, self.g_albedo_spec] {
                gl.delete_texture(t);
            }
            for r in [self.rbo_depth, self.screen_color, self.screen_depth] {
                gl.delete_renderbuffer(r);
            }
            for p in [
                self.shader_geometry_pass,
                self.shader_lighting_pass,
                self.shader_light_box,
            ] {
                gl.delete_program(p);
            }
            for v in [self.scene_vao, self.quad_vao, self.cube_vao] {
                gl.delete_vertex_array(v);
            }
            for b in [self.scene_vbo, self.quad_vbo, self.cube_vbo] {
                gl.delete_buffer(b);
            }
        }
    }
}

fn world_key_options() -> RetrofitOptions {
    RetrofitOptions {
        position_attachment: Some(ColorAttachment(0)),
        position_space: PositionSpace::World,
        ..RetrofitOptions::default()
    }
}

/// The host run through the harness with its world-space position as the key.
pub fn outcome_world_key(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    layers: u32,
) -> harness::Outcome {
    let options = harness::with_layers(
        world_key_options(),
        layers,
        NormalAttachment {
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Xyz,
        },
    );
    harness::run::<LearnOpenGl>(
        ctx,
        &harness::name("learnopengl-world-key", layers),
        &options,
        LearnOpenGl::frame_with_view,
    )
}

/// The tutorial's program with its first light moved into the gap between
/// the floating triangle and the panel behind it, its falloff steep (a
/// small bright light, as an engine places for a lamp): what the paper's
/// halo needs, a position between an edge's two surfaces lit as neither is.
struct GapLit(LearnOpenGl);

impl ZooHost for GapLit {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let host = LearnOpenGl::new(gl, width, height);
        let p = host.shader_lighting_pass;
        unsafe {
            gl.use_program(Some(p));
            set_vec3(
                gl,
                p,
                "lights[0].Position",
                glam::Vec3::new(0.85, 0.8, -0.2),
            );
            set_vec3(gl, p, "lights[0].Color", glam::Vec3::splat(3.0));
            set_float(gl, p, "lights[0].Linear", 0.0);
            set_float(gl, p, "lights[0].Quadratic", 6.0);
            gl.use_program(None);
        }
        GapLit(host)
    }
    fn gbuffer(&self) -> glow::Framebuffer {
        self.0.gbuffer()
    }
    fn screen(&self) -> glow::Framebuffer {
        self.0.screen()
    }
    fn units(&self) -> u32 {
        self.0.units()
    }
    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        self.0.geometry_pass(gl, fbo)
    }
    fn lighting_pass(&self, gl: &glow::Context) {
        self.0.lighting_pass(gl)
    }
    fn read_gbuffer(&self, gl: &glow::Context) -> Vec<Plane> {
        self.0.read_gbuffer(gl)
    }
    fn destroy(self, gl: &glow::Context) {
        self.0.destroy(gl)
    }
}

/// [`GapLit`] with its G-buffer resolved as `glBlitFramebuffer` resolves a
/// multisampled one (`ResolveMethod::Average`: every sample of every
/// attachment averaged, positions and normals too; one layer), or by the
/// default median (`averaged` false). Averaged, its lighting lights
/// positions between the triangle's edge and the panel, close to the
/// light: the halos the zoo's halo check exists to catch
/// (`zoo::a_blit_resolved_gbuffer_has_halo_pixels`).
pub fn outcome_gap_lit(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    averaged: bool,
) -> harness::Outcome {
    let mut options = world_key_options();
    let name = if averaged {
        options.resolve.method = deferred_msaa::resolve::ResolveMethod::Average;
        "learnopengl-gap-lit, averaged"
    } else {
        "learnopengl-gap-lit"
    };
    harness::run::<GapLit>(ctx, name, &options, |h| h.0.frame_with_view())
}

/// The host run through the harness with the default depth key.
pub fn outcome_depth_key(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    layers: u32,
) -> harness::Outcome {
    let options = harness::with_layers(
        RetrofitOptions::default(),
        layers,
        NormalAttachment {
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Xyz,
        },
    );
    harness::run::<LearnOpenGl>(
        ctx,
        &harness::name("learnopengl-depth-key", layers),
        &options,
        LearnOpenGl::frame,
    )
}

#[test]
fn the_tutorial_layout_with_its_world_space_position_as_the_key() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome_world_key(&ctx, 1).assert_ok();
}

#[test]
fn the_tutorial_layout_with_the_default_depth_key() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome_depth_key(&ctx, 1).assert_ok();
}

#[test]
fn a_world_space_key_without_the_view_matrix_is_refused_in_one_line() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let v = gl.version();
    if (v.major, v.minor) < LearnOpenGl::needs_gl() {
        eprintln!("not run: the tutorial's shaders need OpenGL 3.3");
        return;
    }
    let host = LearnOpenGl::new(gl, W, harness::H);
    let mut msaa = deferred_msaa::MsaaRetrofit::new(gl, host.gbuffer(), &world_key_options())
        .expect("the tutorial layout is accepted");
    host.geometry_pass(gl, msaa.begin_frame(gl).unwrap());
    let error = msaa
        .resolve(gl, &host.frame())
        .expect_err("a world-space key needs the view matrix");
    let text = error.to_string();
    assert!(
        matches!(error, deferred_msaa::Error::InvalidArgument(_)),
        "{error:?}"
    );
    assert_eq!(text.lines().count(), 1, "{text}");
    // With the view it resolves.
    msaa.resolve(gl, &host.frame_with_view())
        .expect("with the view matrix");
    msaa.destroy(gl);
    host.destroy(gl);
    assert_eq!(deferred_msaa::gl::live_objects().total(), 0);
}
