//! A tiny host renderer written here — its own textures and FBO, its own
//! mesh upload and draw loop, the renderer's model and lighting shaders
//! used unchanged — retrofitted through the public API alone, gives the same
//! resolved G-buffer and the same lit image as the built-in pipeline.

use crate::common;

use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, NormalAttachment};
use deferred_msaa_lab::gbuffer::GBufferLayout;
use deferred_msaa_lab::gl::{
    Attachment, Buffer, Format, Framebuffer, Program, ShaderStage, Texture2d, TextureRef,
    VertexArray, live_objects, preamble,
};
use deferred_msaa_lab::readback::{Readback, SampleImage};
use deferred_msaa_lab::renderer::{AaMode, DepthMode, RenderOptions, Renderer, shaders};
use deferred_msaa_lab::resolve::{KeySource, ResolveMethod, ResolveSettings, ResolveSlot};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::scene::{AlphaMode, Background, LightKind, Material, Scene};
use glam::{DMat4, DVec3};
use glow::HasContext;

const W: u32 = 128;
const H: u32 = 72;

/// The host's own full-screen vertex shader (the lighting shader only reads
/// `gl_FragCoord`).
const HOST_FULLSCREEN_VERT: &str = "
void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
";

/// One object as the host uploads it.
struct HostMesh {
    vao: VertexArray,
    buffers: Vec<Buffer>,
    count: i32,
    model: DMat4,
    material: Material,
}

/// The host engine: a G-buffer of `layout`'s formats on its own FBO.
struct Host {
    colors: Vec<Texture2d>,
    depth: Texture2d,
    fbo: Framebuffer,
    model: Program,
    meshes: Vec<HostMesh>,
    white: Texture2d,
}

impl Host {
    fn new(gl: &glow::Context, layout: &GBufferLayout, scene: &Scene) -> Host {
        let colors: Vec<Texture2d> = layout
            .colors
            .iter()
            .map(|a| Texture2d::new(gl, &format!("host {}", a.name), a.format, W, H).unwrap())
            .collect();
        let depth = Texture2d::new(gl, "host depth", layout.depth, W, H).unwrap();
        let mut attachments: Vec<(Attachment, TextureRef)> = colors
            .iter()
            .enumerate()
            .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
            .collect();
        attachments.push((
            Attachment::for_depth_format(depth.format),
            TextureRef::from(&depth),
        ));
        let draw: Vec<Option<u32>> = (0..colors.len() as u32).map(Some).collect();
        let fbo = Framebuffer::new(gl, "host gbuffer", &attachments, &draw).unwrap();
        let slot = |name: &str| layout.index_of(name).unwrap() as u32;
        let outputs = ["color", "position", "normal", "specular", "emissive"]
            .map(|n| (format!("o_{n}"), slot(n)));
        let outputs: Vec<(&str, u32)> = outputs.iter().map(|(n, k)| (n.as_str(), *k)).collect();
        let model = Program::build(
            gl,
            "host model",
            &preamble(&[], &[]),
            &[
                (ShaderStage::Vertex, "geometry.vert", shaders::GEOMETRY_VERT),
                (
                    ShaderStage::Fragment,
                    "geometry.frag",
                    shaders::GEOMETRY_FRAG,
                ),
            ],
            &outputs,
        )
        .unwrap();
        let white =
            Texture2d::with_data(gl, "host white", Format::Rgba8, 1, 1, Some(&[255; 4])).unwrap();
        let attrib = |name: &str| unsafe { gl.get_attrib_location(model.raw(), name) };
        let mut meshes = Vec::new();
        for o in scene.objects.iter().filter(|o| o.indices.len() >= 3) {
            let material = scene.material_of(o);
            assert!(
                material.alpha_mode != AlphaMode::Blend,
                "greebles has no transparent objects"
            );
            assert!(material.base_color_texture.is_none() && material.emissive_texture.is_none());
            let vao = VertexArray::new(gl, &o.name).unwrap();
            vao.bind(gl);
            let mut buffers = Vec::new();
            let streams: [(&str, &[u8], i32); 3] = [
                ("a_position", bytemuck::cast_slice(&o.positions), 3),
                ("a_normal", bytemuck::cast_slice(&o.normals), 3),
                ("a_uv", bytemuck::cast_slice(&o.uvs), 2),
            ];
            for (name, data, size) in streams {
                let b = Buffer::with_data(gl, name, glow::ARRAY_BUFFER, data, glow::STATIC_DRAW)
                    .unwrap();
                if let Some(loc) = attrib(name) {
                    unsafe {
                        gl.bind_buffer(glow::ARRAY_BUFFER, Some(b.raw()));
                        gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, 0, 0);
                        gl.enable_vertex_attrib_array(loc);
                    }
                }
                buffers.push(b);
            }
            let indices = bytemuck::cast_slice(&o.indices);
            let ib = Buffer::with_data(
                gl,
                "indices",
                glow::ELEMENT_ARRAY_BUFFER,
                indices,
                glow::STATIC_DRAW,
            )
            .unwrap();
            unsafe {
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ib.raw()));
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
            }
            buffers.push(ib);
            meshes.push(HostMesh {
                vao,
                buffers,
                count: o.indices.len() as i32,
                model: o.transform.as_dmat4(),
                material,
            });
        }
        Host {
            colors,
            depth,
            fbo,
            model,
            meshes,
            white,
        }
    }

    /// The host's geometry pass into the bound framebuffer (MSAA's twin).
    fn draw(&self, gl: &glow::Context, emissive: u32, view: &DMat4, projection: &[f32; 16]) {
        unsafe {
            gl.viewport(0, 0, W as i32, H as i32);
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            // A black background: what the renderer's copy pass leaves.
            gl.clear_buffer_f32_slice(glow::COLOR, emissive, &[0.0, 0.0, 0.0, 1.0]);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.disable(glow::BLEND);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.enable(glow::MULTISAMPLE);
            for unit in 0..2 {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, Some(self.white.raw()));
            }
        }
        let p = &self.model;
        p.bind(gl);
        p.set_mat4(gl, "u_projection", projection);
        p.set_i32(gl, "u_base_texture", 0);
        p.set_i32(gl, "u_emissive_texture", 1);
        for m in &self.meshes {
            let model_view = *view * m.model;
            let normal = model_view.inverse().transpose();
            let normal = if normal.is_finite() {
                normal
            } else {
                DMat4::IDENTITY
            };
            p.set_mat4(gl, "u_model_view", &model_view.as_mat4().to_cols_array());
            p.set_mat4(gl, "u_normal_matrix", &normal.as_mat4().to_cols_array());
            let mat = &m.material;
            p.set_vec4(gl, "u_base_color", mat.base_color);
            p.set_f32(gl, "u_metallic", mat.metallic);
            p.set_f32(gl, "u_roughness", mat.roughness);
            p.set_vec3(gl, "u_emissive", mat.emissive);
            let cutoff = if mat.alpha_mode == AlphaMode::Mask {
                mat.alpha_cutoff
            } else {
                -1.0
            };
            p.set_f32(gl, "u_alpha_cutoff", cutoff);
            p.set_i32(gl, "u_double_sided", mat.double_sided as i32);
            unsafe {
                if mat.double_sided {
                    gl.disable(glow::CULL_FACE);
                } else {
                    gl.enable(glow::CULL_FACE);
                    gl.cull_face(glow::BACK);
                    gl.front_face(glow::CCW);
                }
                m.vao.bind(gl);
                gl.draw_elements(glow::TRIANGLES, m.count, glow::UNSIGNED_INT, 0);
            }
        }
        unsafe { gl.bind_vertex_array(None) };
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        for t in self.colors.into_iter().chain([self.depth, self.white]) {
            t.destroy(gl);
        }
        self.model.destroy(gl);
        for m in self.meshes {
            m.vao.destroy(gl);
            for b in m.buffers {
                b.destroy(gl);
            }
        }
    }
}

/// The host's lighting pass: the renderer's lighting shader, unchanged, on
/// the host's resolved textures; returns the HDR image.
fn host_lighting(
    gl: &glow::Context,
    host: &Host,
    layout: &GBufferLayout,
    scene: &Scene,
    view: &DMat4,
) -> SampleImage {
    let program = Program::build(
        gl,
        "host lighting",
        &preamble(&[], &shaders::lighting_defines()),
        &[
            (
                ShaderStage::Vertex,
                "host fullscreen.vert",
                HOST_FULLSCREEN_VERT,
            ),
            (
                ShaderStage::Fragment,
                "lighting.frag",
                shaders::LIGHTING_FRAG,
            ),
        ],
        &[("o_color", 0)],
    )
    .unwrap();
    let hdr = Texture2d::new(gl, "host hdr", Format::Rgba16f, W, H).unwrap();
    let fbo = Framebuffer::new(
        gl,
        "host hdr",
        &[(Attachment::Color(0), TextureRef::from(&hdr))],
        &[Some(0)],
    )
    .unwrap();
    let vao = VertexArray::new(gl, "host fullscreen").unwrap();
    // The lights in view space, packed as lighting.frag documents them.
    assert!(
        scene.lights.len() <= shaders::LIGHTS_PER_BATCH,
        "one batch of lights"
    );
    let (mut position, mut direction, mut colour, mut cone) = (vec![], vec![], vec![], vec![]);
    for l in &scene.lights {
        let p = view.transform_point3(l.position.as_dvec3()).as_vec3();
        let d = view
            .transform_vector3(l.direction.as_dvec3())
            .normalize_or(DVec3::NEG_Z)
            .as_vec3();
        let range = l.range.filter(|r| r.is_finite() && *r > 0.0).unwrap_or(0.0);
        let (kind, c) = match l.kind {
            LightKind::Point => (0.0, [0.0; 4]),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => (1.0, [outer_cone.cos(), inner_cone.cos(), 0.0, 0.0]),
            LightKind::Directional => (2.0, [0.0; 4]),
        };
        let rgb = l.color * l.intensity;
        position.push([p.x, p.y, p.z, range]);
        direction.push([d.x, d.y, d.z, kind]);
        colour.push([rgb.x, rgb.y, rgb.z, 0.0]);
        cone.push(c);
    }
    unsafe {
        fbo.bind(gl);
        gl.viewport(0, 0, W as i32, H as i32);
        gl.disable(glow::DEPTH_TEST);
        gl.disable(glow::BLEND);
        gl.disable(glow::CULL_FACE);
    }
    let p = &program;
    p.bind(gl);
    let inputs = ["color", "position", "normal", "specular", "emissive"]
        .map(|n| (format!("u_{n}"), &host.colors[layout.index_of(n).unwrap()]));
    for (unit, (name, texture)) in inputs
        .iter()
        .map(|(n, t)| (n.as_str(), *t))
        .chain([("u_depth", &host.depth)])
        .enumerate()
    {
        unsafe {
            gl.active_texture(glow::TEXTURE0 + unit as u32);
            gl.bind_texture(glow::TEXTURE_2D, Some(texture.raw()));
        }
        p.set_i32(gl, name, unit as i32);
    }
    p.set_f32(gl, "u_clear_depth", 1.0);
    p.set_i32(gl, "u_light_count", position.len() as i32);
    p.set_vec4_array(gl, "u_light_position[0]", &position);
    p.set_vec4_array(gl, "u_light_direction[0]", &direction);
    p.set_vec4_array(gl, "u_light_color[0]", &colour);
    p.set_vec4_array(gl, "u_light_cone[0]", &cone);
    p.set_vec3(gl, "u_ambient", shaders::AMBIENT);
    p.set_i32(gl, "u_first_batch", 1);
    vao.bind(gl);
    unsafe {
        gl.draw_arrays(glow::TRIANGLES, 0, 3);
        gl.bind_vertex_array(None);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
    let mut readback = Readback::new(gl).unwrap();
    let image = readback.read(gl, TextureRef::from(&hdr), 1).unwrap();
    readback.destroy(gl);
    program.destroy(gl);
    fbo.destroy(gl);
    hdr.destroy(gl);
    vao.destroy(gl);
    image
}

/// The largest difference between two images, counting a mismatch in
/// finiteness as infinite; and where it is.
fn max_difference(a: &SampleImage, b: &SampleImage) -> (f32, usize) {
    assert_eq!(
        (a.width, a.height, a.samples),
        (b.width, b.height, b.samples)
    );
    a.data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| match (x.is_finite(), y.is_finite()) {
            (true, true) => (x - y).abs(),
            _ if x.to_bits() == y.to_bits() => 0.0,
            _ => f32::INFINITY,
        })
        .enumerate()
        .fold(
            (0.0, 0),
            |(m, at), (i, d)| if d > m { (d, i / 4) } else { (m, at) },
        )
}

#[test]
fn a_host_retrofitted_through_the_public_api_matches_the_builtin_pipeline() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut scene = Scene::load("builtin:greebles").expect("scene");
    // The host draws no background of its own: black on both sides.
    scene.background = Background::Black;
    let layout = GBufferLayout::recommended();
    let settings = ResolveSettings {
        method: ResolveMethod::Median,
        ..ResolveSettings::default()
    };
    let options = RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa: AaMode::Resolve(settings),
        fxaa: false,
        layout: layout.clone(),
        // The host has every attachment: compare like with like.
        adaptive: false,
        depth_mode: DepthMode::Standard,
        ..RenderOptions::default()
    };

    // The built-in pipeline.
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &options).expect("renderer");
    renderer.render(gl).expect("frame");
    let mut readback = Readback::new(gl).unwrap();
    let gb = renderer.gbuffer();
    let expected: Vec<SampleImage> = gb
        .colors
        .iter()
        .chain([&gb.depth])
        .map(|t| readback.read(gl, TextureRef::from(t), 1).unwrap())
        .collect();
    let expected_hdr = readback.read(gl, renderer.hdr_texture(), 1).unwrap();

    // The host: its own projection and resolve parameters, from the camera.
    let camera = scene.camera;
    let projection = camera.projection(W as f32 / H as f32);
    assert_eq!(projection, renderer.projection());
    let frame = deferred_msaa::Frame::from_matrix(projection.to_cols_array());
    assert_eq!(frame, renderer.resolve_frame());
    let host = Host::new(gl, &layout, &scene);
    let retrofit_options = RetrofitOptions {
        samples: 4,
        rules: layout
            .colors
            .iter()
            .enumerate()
            .map(|(k, a)| (ColorAttachment(k as u32), a.rule))
            .collect(),
        position_attachment: match layout.key {
            KeySource::Position(ResolveSlot(k)) => Some(ColorAttachment(k as u32)),
            other => panic!("the demo layout keys on view-space position, not {other:?}"),
        },
        resolve: settings,
        // The layout's normals, xyz, named as the renderer names them.
        normal_attachment: layout.index_of("normal").map(|k| NormalAttachment {
            attachment: ColorAttachment(k as u32),
            encoding: NormalEncoding::Xyz,
        }),
        ..RetrofitOptions::default()
    };
    assert_eq!(
        Some(&retrofit_options.resolve),
        renderer.retrofit().map(|r| &r.options().resolve)
    );
    // The two integration lines.
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &retrofit_options).expect("retrofit");
    assert_eq!(msaa.samples(), renderer.samples());
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    let emissive = layout.index_of("emissive").unwrap() as u32;
    host.draw(
        gl,
        emissive,
        &camera.view.as_dmat4(),
        &projection.to_cols_array(),
    );
    msaa.resolve(gl, &frame).expect("resolve");

    // Every attachment, every pixel.
    let names: Vec<&str> = layout
        .colors
        .iter()
        .map(|a| a.name.as_str())
        .chain(["depth"])
        .collect();
    for ((name, texture), want) in names
        .iter()
        .zip(host.colors.iter().chain([&host.depth]))
        .zip(&expected)
    {
        let got = readback.read(gl, TextureRef::from(texture), 1).unwrap();
        let (diff, at) = max_difference(&got, want);
        eprintln!("{name}: max difference {diff:e}");
        assert!(
            diff <= 1e-3,
            "{name}: the host's resolved value differs by {diff} at pixel ({}, {})",
            at % W as usize,
            at / W as usize
        );
    }
    readback.destroy(gl);

    // The lit image: the renderer's lighting shader, unchanged, on the host's G-buffer.
    let hdr = host_lighting(gl, &host, &layout, &scene, &camera.view.as_dmat4());
    let lit = hdr
        .data
        .chunks_exact(4)
        .filter(|p| p[0] + p[1] + p[2] > 0.01)
        .count();
    assert!(
        lit > (W * H) as usize / 10,
        "only {lit} lit pixels: nothing to compare"
    );
    let (diff, at) = max_difference(&hdr, &expected_hdr);
    let peak = expected_hdr
        .data
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f32::max);
    eprintln!("lit HDR: max difference {diff:e} (peak {peak})");
    assert!(
        diff <= 1e-3 * peak.max(1.0),
        "lit HDR differs by {diff} at pixel ({}, {})",
        at % W as usize,
        at / W as usize
    );

    msaa.destroy(gl);
    host.destroy(gl);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}
