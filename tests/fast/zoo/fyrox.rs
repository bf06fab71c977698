//! A G-buffer laid out the way the Fyrox engine lays out its own: diffuse
//! colour in a plain `GL_RGBA8` texture that holds sRGB-encoded values (the
//! model shader writes the albedo as it read it from an sRGB texture, and
//! the lighting decodes it); world-space normals packed `n * 0.5 + 0.5`
//! into `GL_RGB10_A2`; ambient light plus emission in `GL_RGB10_A2`;
//! metallic, roughness and ambient occlusion in `GL_RGBA8`; a decal mask,
//! the decal layer an object accepts, in `GL_R8UI`; one
//! `GL_DEPTH24_STENCIL8` texture at `GL_DEPTH_STENCIL_ATTACHMENT`. Every
//! texture is allocated with `glTexImage2D` and a sized internal format,
//! as Fyrox's GL back end does, and the G-buffer is cleared to zero with
//! depth 1 and stencil 0 in one `glClear`. The lighting rebuilds the world
//! position from depth with the inverse view-projection and normalises the
//! unpacked normal, so a blend of two packed normals at a crease lights as
//! the normal halfway between the faces: neither face's light. (Fyrox
//! accumulates lights additively into an HDR target and tonemaps later;
//! this host does both in one pass over its two lights, since the harness
//! reads its image as 8-bit RGBA.)

use super::harness::{self, Channel, Check, Plane, Read, ZooHost};
use super::scene;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, NormalAttachment, RetrofitOptions};
use glow::HasContext;

const MODEL_VS: &str = r#"#version 330 core
layout (location = 0) in vec3 vertexPosition;
layout (location = 1) in vec3 vertexNormal;
layout (location = 2) in vec3 vertexColor;
layout (location = 3) in float vertexMaterial;
uniform mat4 worldViewProjection;
out vec3 normal;
out vec3 color;
flat out int material;
void main() {
    normal = vertexNormal;
    color = vertexColor;
    material = int(vertexMaterial);
    gl_Position = worldViewProjection * vec4(vertexPosition, 1.0);
}
"#;

const MODEL_FS: &str = r#"#version 330 core
in vec3 normal;
in vec3 color;
flat in int material;
layout (location = 0) out vec4 outColor;
layout (location = 1) out vec4 outNormal;
layout (location = 2) out vec4 outAmbient;
layout (location = 3) out vec4 outMaterial;
layout (location = 4) out uint outDecalMask;
void main() {
    // The albedo as an sRGB texture stores it, into a linear RGBA8 target.
    outColor = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
    outNormal = vec4(normalize(normal) * 0.5 + 0.5, 1.0);
    float emission = material == 4 ? 0.35 : 0.0;
    outAmbient = vec4(vec3(0.06) + emission * color, 1.0);
    float roughness = material == 2 ? 0.25 : 0.6;
    outMaterial = vec4(material == 3 ? 1.0 : 0.0, roughness, 1.0, 1.0);
    outDecalMask = uint(material);
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
uniform sampler2D diffuseTexture;
uniform sampler2D normalTexture;
uniform sampler2D ambientTexture;
uniform sampler2D materialTexture;
uniform sampler2D depthTexture;
uniform mat4 invViewProj;
uniform vec3 cameraPosition;
uniform vec2 resolution;
uniform vec3 lightPosition[2];
uniform vec3 lightColor[2];
out vec4 FragColor;

void main() {
    vec2 texCoord = gl_FragCoord.xy / resolution;
    float depth = texture(depthTexture, texCoord).r;
    if (depth == 1.0) {
        FragColor = vec4(0.55, 0.7, 0.9, 1.0);
        return;
    }
    vec4 clip = vec4(texCoord * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec4 world = invViewProj * clip;
    vec3 fragmentPosition = world.xyz / world.w;
    vec3 albedo = pow(texture(diffuseTexture, texCoord).rgb, vec3(2.2));
    vec3 n = normalize(texture(normalTexture, texCoord).xyz * 2.0 - 1.0);
    vec4 m = texture(materialTexture, texCoord);
    float metallic = m.x;
    float roughness = max(m.y, 0.05);
    vec3 v = normalize(cameraPosition - fragmentPosition);
    vec3 f0 = mix(vec3(0.04), albedo, metallic);
    vec3 c = texture(ambientTexture, texCoord).rgb * albedo * m.z;
    for (int i = 0; i < 2; ++i) {
        vec3 l = lightPosition[i] - fragmentPosition;
        float attenuation = 1.0 / (1.0 + dot(l, l));
        l = normalize(l);
        vec3 h = normalize(l + v);
        float nl = max(dot(n, l), 0.0);
        float nv = max(dot(n, v), 1e-4);
        float nh = max(dot(n, h), 0.0);
        float a2 = roughness * roughness * roughness * roughness;
        float den = nh * nh * (a2 - 1.0) + 1.0;
        float d = a2 / (PI * den * den);
        float k = (roughness + 1.0) * (roughness + 1.0) / 8.0;
        float g = nl / (nl * (1.0 - k) + k) * nv / (nv * (1.0 - k) + k);
        vec3 f = f0 + (1.0 - f0) * pow(1.0 - max(dot(h, v), 0.0), 5.0);
        vec3 specular = d * g * f / max(4.0 * nl * nv, 1e-4);
        vec3 diffuse = (1.0 - f) * (1.0 - metallic) * albedo / PI;
        c += (diffuse + specular) * lightColor[i] * 14.0 * nl * attenuation;
    }
    c = c / (1.0 + c);
    FragColor = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}
"#;

/// The Fyrox-style engine.
pub struct FyroxEngine {
    width: i32,
    height: i32,
    gbuffer: glow::Framebuffer,
    diffuse: glow::Texture,
    normal: glow::Texture,
    ambient: glow::Texture,
    material: glow::Texture,
    decal_mask: glow::Texture,
    depth_stencil: glow::Texture,
    screen: glow::Framebuffer,
    screen_color: glow::Texture,
    model: glow::Program,
    lighting: glow::Program,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    count: i32,
    quad_vao: glow::VertexArray,
}

impl FyroxEngine {
    /// What it passes to the resolve: its projection.
    pub fn frame(&self) -> Frame {
        Frame::from_matrix(scene::projection(self.width as u32, self.height as u32).to_cols_array())
    }
}

impl ZooHost for FyroxEngine {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self {
        let (w, h) = (width as i32, height as i32);
        unsafe {
            // Rectangle textures: nearest filtering, clamped, one level.
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
                for (p, v) in [
                    (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
                    (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
                    (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE),
                    (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE),
                    (glow::TEXTURE_MAX_LEVEL, 0),
                ] {
                    gl.tex_parameter_i32(glow::TEXTURE_2D, p, v as i32);
                }
                t
            };
            let depth_stencil = texture(
                glow::DEPTH24_STENCIL8,
                glow::DEPTH_STENCIL,
                glow::UNSIGNED_INT_24_8,
            );
            let diffuse = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let normal = texture(
                glow::RGB10_A2,
                glow::RGBA,
                glow::UNSIGNED_INT_2_10_10_10_REV,
            );
            let ambient = texture(
                glow::RGB10_A2,
                glow::RGBA,
                glow::UNSIGNED_INT_2_10_10_10_REV,
            );
            let material = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let decal_mask = texture(glow::R8UI, glow::RED_INTEGER, glow::UNSIGNED_BYTE);
            let screen_color = texture(glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE);
            let gbuffer = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(gbuffer));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(depth_stencil),
                0,
            );
            let colors = [diffuse, normal, ambient, material, decal_mask];
            for (i, t) in colors.iter().enumerate() {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::COLOR_ATTACHMENT0 + i as u32,
                    glow::TEXTURE_2D,
                    Some(*t),
                    0,
                );
            }
            let buffers: Vec<u32> = (0..colors.len() as u32)
                .map(|i| glow::COLOR_ATTACHMENT0 + i)
                .collect();
            gl.draw_buffers(&buffers);
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

            let model = harness::program(gl, "fyrox gbuffer", MODEL_VS, MODEL_FS);
            let lighting = harness::program(gl, "fyrox lighting", FULLSCREEN_VS, LIGHTING_FS);
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
            let quad_vao = gl.create_vertex_array().unwrap();

            gl.use_program(Some(lighting));
            for (unit, (name, t)) in [
                ("diffuseTexture", diffuse),
                ("normalTexture", normal),
                ("ambientTexture", ambient),
                ("materialTexture", material),
                ("depthTexture", depth_stencil),
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
            let loc = gl.get_uniform_location(lighting, "invViewProj");
            gl.uniform_matrix_4_f32_slice(
                loc.as_ref(),
                false,
                &view_projection.inverse().to_cols_array(),
            );
            let loc = gl.get_uniform_location(lighting, "cameraPosition");
            gl.uniform_3_f32(loc.as_ref(), scene::EYE.x, scene::EYE.y, scene::EYE.z);
            let loc = gl.get_uniform_location(lighting, "resolution");
            gl.uniform_2_f32(loc.as_ref(), w as f32, h as f32);
            for (i, (p, c)) in scene::LIGHTS.iter().enumerate() {
                let loc = gl.get_uniform_location(lighting, &format!("lightPosition[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), p.x, p.y, p.z);
                let loc = gl.get_uniform_location(lighting, &format!("lightColor[{i}]"));
                gl.uniform_3_f32(loc.as_ref(), c.x, c.y, c.z);
            }
            gl.use_program(None);
            gl.enable(glow::CULL_FACE);
            gl.cull_face(glow::BACK);
            FyroxEngine {
                width: w,
                height: h,
                gbuffer,
                diffuse,
                normal,
                ambient,
                material,
                decal_mask,
                depth_stencil,
                screen,
                screen_color,
                model,
                lighting,
                vao,
                vbo,
                count: (data.len() / 10) as i32,
                quad_vao,
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
        5
    }

    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, self.width, self.height);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear_stencil(0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LEQUAL);
            gl.disable(glow::BLEND);
            gl.use_program(Some(self.model));
            let vp = scene::projection(self.width as u32, self.height as u32) * scene::view();
            let loc = gl.get_uniform_location(self.model, "worldViewProjection");
            gl.uniform_matrix_4_f32_slice(loc.as_ref(), false, &vp.to_cols_array());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::TRIANGLES, 0, self.count);
            gl.bind_vertex_array(None);
        }
    }

    fn lighting_pass(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.screen));
            gl.viewport(0, 0, self.width, self.height);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.use_program(Some(self.lighting));
            gl.bind_vertex_array(Some(self.quad_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            gl.use_program(None);
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
                self.diffuse,
                "diffuse GL_COLOR_ATTACHMENT0 (GL_RGBA8, sRGB-encoded values)",
                glow::RGBA,
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            read(
                self.normal,
                "packed normal GL_COLOR_ATTACHMENT1 (GL_RGB10_A2)",
                glow::RGBA,
                4,
                Channel::F32,
                Check::Constant,
            ),
            read(
                self.ambient,
                "ambient and emission GL_COLOR_ATTACHMENT2 (GL_RGB10_A2)",
                glow::RGBA,
                4,
                Channel::F32,
                Check::Constant,
            ),
            read(
                self.material,
                "material GL_COLOR_ATTACHMENT3 (GL_RGBA8)",
                glow::RGBA,
                4,
                Channel::Unorm8,
                Check::Constant,
            ),
            read(
                self.decal_mask,
                "decal mask GL_COLOR_ATTACHMENT4 (GL_R8UI)",
                glow::RED_INTEGER,
                1,
                Channel::U8,
                Check::Constant,
            ),
            read(
                self.depth_stencil,
                "depth of GL_DEPTH_STENCIL_ATTACHMENT (GL_DEPTH24_STENCIL8)",
                glow::DEPTH_COMPONENT,
                1,
                Channel::F32,
                Check::Smooth,
            ),
        ]
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.disable(glow::CULL_FACE);
            gl.delete_framebuffer(self.gbuffer);
            gl.delete_framebuffer(self.screen);
            for t in [
                self.diffuse,
                self.normal,
                self.ambient,
                self.material,
                self.decal_mask,
                self.depth_stencil,
                self.screen_color,
            ] {
                gl.delete_texture(t);
            }
            gl.delete_program(self.model);
            gl.delete_program(self.lighting);
            gl.delete_vertex_array(self.vao);
            gl.delete_vertex_array(self.quad_vao);
            gl.delete_buffer(self.vbo);
        }
    }
}

/// The host through the harness with `layers` layers; with two, its
/// packed normals named, so that the second layer's clusters split at the
/// box's creases. The integration adds nothing else: its position comes
/// from depth and every format resolves by its default rule (the decal
/// mask, an integer, takes the reference sample's).
pub fn outcome(ctx: &deferred_msaa_lab::context::HeadlessContext, layers: u32) -> harness::Outcome {
    let options = harness::with_layers(
        RetrofitOptions::default(),
        layers,
        NormalAttachment {
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Unorm,
        },
    );
    harness::run::<FyroxEngine>(
        ctx,
        &harness::name("fyrox", layers),
        &options,
        FyroxEngine::frame,
    )
}

#[test]
fn a_fyrox_style_gbuffer_with_packed_normals_and_a_depth_stencil_texture() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    outcome(&ctx, 1).assert_ok();
}

/// One layer, its packed normals named, and not: the normal test is part
/// of the one-layer resolve (the two images differ, and both pass the
/// zoo's checks). Measured here (96x64, the zoo's scene): halo pixels none
/// 8, one layer 19 named or not; the one layer's halos are at silhouettes
/// against the sky, which only the second layer mends (0 with two), not
/// at the box's creases, so this scene does not show the specks a blend of
/// packed normals makes where two faces meet at equal depth.
#[test]
fn one_layer_splits_clusters_by_the_named_packed_normals() {
    let Some(ctx) = crate::common::egl_context() else {
        return;
    };
    let named = outcome(&ctx, 1);
    named.assert_ok();
    if named.not_run.is_some() {
        // The host's own shaders need a newer context (the 3.2 floor run).
        return;
    }
    let unnamed = harness::run::<FyroxEngine>(
        &ctx,
        "fyrox (normals not named)",
        &RetrofitOptions::default(),
        FyroxEngine::frame,
    );
    unnamed.assert_ok();
    eprintln!(
        "fyrox, one layer: halo pixels none {}, normals named {}, not named {}; FLIP named {:.4}, not named {:.4}",
        named.halos_none,
        named.halos_resolved,
        unnamed.halos_resolved,
        named.flip_resolved,
        unnamed.flip_resolved
    );
    assert!(
        named.flip_resolved != unnamed.flip_resolved,
        "naming the normal attachment left the one-layer resolve unchanged (FLIP {})",
        named.flip_resolved
    );
}
