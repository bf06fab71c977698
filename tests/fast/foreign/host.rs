//! The glow 0.17 host: its shaders, its scene, its G-buffer and lighting,
//! and its images read back (the lit image, the edges, its own 16x image).

use crate::common;
use glow017::HasContext;
use image::RgbaImage;

pub(super) const W: i32 = 96;
pub(super) const H: i32 = 64;
pub(super) const NEAR: f32 = 0.5;
pub(super) const FAR: f32 = 50.0;

/// The engine's geometry shader: view-space positions through its
/// projection, albedo and view-space normal out to two attachments.
pub(super) const GEOMETRY_VS: &str = r#"#version 150
in vec3 position;
in vec3 color;
in vec3 normal;
uniform mat4 projection;
out vec3 v_color;
out vec3 v_normal;
void main() {
    v_color = color;
    v_normal = normal;
    gl_Position = projection * vec4(position, 1.0);
}
"#;

pub(super) const GEOMETRY_FS: &str = r#"#version 150
in vec3 v_color;
in vec3 v_normal;
out vec4 albedo;
out vec4 normal;
void main() {
    albedo = vec4(v_color, 1.0);
    normal = vec4(normalize(v_normal), 0.0);
}
"#;

/// The engine's lighting: one directional light and an ambient term, read
/// from its G-buffer by texel; the background where the depth is clear.
pub(super) const LIGHTING_VS: &str = r#"#version 150
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
"#;

pub(super) const LIGHTING_FS: &str = r#"#version 150
uniform sampler2D g_albedo;
uniform sampler2D g_normal;
uniform sampler2D g_depth;
uniform vec3 light_dir;
out vec4 lit;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (texelFetch(g_depth, p, 0).r >= 1.0) {
        lit = vec4(0.05, 0.05, 0.08, 1.0);
        return;
    }
    vec3 albedo = texelFetch(g_albedo, p, 0).rgb;
    vec3 n = normalize(texelFetch(g_normal, p, 0).xyz);
    float diffuse = max(dot(n, normalize(light_dir)), 0.0);
    // The engine encodes for the screen in its shader; GL_FRAMEBUFFER_SRGB
    // stays off.
    vec3 c = clamp(albedo * (0.15 + 0.85 * diffuse), 0.0, 1.0);
    lit = vec4(mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308))), 1.0);
}
"#;

/// A symmetric perspective projection, column-major.
pub(super) fn projection() -> [f32; 16] {
    let f = 1.0 / (30f32.to_radians()).tan();
    let aspect = W as f32 / H as f32;
    let (a, b) = ((FAR + NEAR) / (NEAR - FAR), 2.0 * FAR * NEAR / (NEAR - FAR));
    [
        f / aspect,
        0.0,
        0.0,
        0.0, //
        0.0,
        f,
        0.0,
        0.0, //
        0.0,
        0.0,
        a,
        -1.0, //
        0.0,
        0.0,
        b,
        0.0,
    ]
}

/// The scene, as triangles of (position, colour, normal): a back wall, a
/// slanted plate in front of it, decals on the wall and bars crossing
/// both at angles.
pub(super) fn scene() -> Vec<f32> {
    let mut v = Vec::new();
    let mut quad = |corners: [[f32; 3]; 4], color: [f32; 3]| {
        let e1 = sub(corners[1], corners[0]);
        let e2 = sub(corners[3], corners[0]);
        let n = normalize(cross(e1, e2));
        for i in [0, 1, 2, 0, 2, 3] {
            v.extend_from_slice(&corners[i]);
            v.extend_from_slice(&color);
            v.extend_from_slice(&n);
        }
    };
    // The wall, facing the camera.
    quad(
        [
            [-8.0, -6.0, -12.0],
            [8.0, -6.0, -12.0],
            [8.0, 6.0, -12.0],
            [-8.0, 6.0, -12.0],
        ],
        [0.55, 0.5, 0.45],
    );
    // A plate turned towards the light, its edges slanted on screen.
    quad(
        [
            [-2.6, -1.4, -6.5],
            [0.4, -2.0, -5.0],
            [1.0, 1.2, -5.5],
            [-2.2, 1.6, -7.0],
        ],
        [0.9, 0.3, 0.2],
    );
    // Decals on the wall, turned squares just in front of it: edges
    // between samples close in depth, which the one-layer resolve blends.
    for k in 0..5 {
        let t = k as f32;
        let (cx, cy, r, a) = (-6.0 + 3.0 * t, 2.5 - 1.2 * t, 1.3, 0.3 + 0.25 * t);
        let corner = |i: f32| {
            let angle = a + i * std::f32::consts::FRAC_PI_2;
            [cx + r * angle.cos(), cy + r * angle.sin(), -11.97]
        };
        quad(
            [corner(0.0), corner(1.0), corner(2.0), corner(3.0)],
            [0.1 + 0.2 * t, 0.9 - 0.15 * t, 0.95 - 0.1 * t],
        );
    }
    // Bars 1 to 5 pixels wide, at angles.
    for k in 0..6 {
        let t = k as f32;
        let (x0, x1) = (-3.0 + 1.1 * t, -1.6 + 1.1 * t);
        let width = 0.08 + 0.06 * t;
        let z = -4.0 - 0.4 * t;
        quad(
            [
                [x0, -2.5, z],
                [x0 + width, -2.5, z],
                [x1 + width, 2.5, z - 0.8],
                [x1, 2.5, z - 0.8],
            ],
            [0.2 + 0.12 * t, 0.8 - 0.1 * t, 0.3],
        );
    }
    v
}

pub(super) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// A deferred engine written on glow 0.17: its G-buffer framebuffer (albedo
/// RGBA8, normal RGBA16F, depth 24-bit textures), its lit framebuffer
/// (RGBA8), its two programs and its mesh.
pub(super) struct Host017 {
    pub(super) width: i32,
    pub(super) height: i32,
    pub(super) gbuffer: glow017::Framebuffer,
    pub(super) albedo: glow017::Texture,
    pub(super) normal: glow017::Texture,
    pub(super) depth: glow017::Texture,
    pub(super) lit_fbo: glow017::Framebuffer,
    pub(super) lit: glow017::Texture,
    pub(super) geometry: glow017::Program,
    pub(super) lighting: glow017::Program,
    pub(super) vao: glow017::VertexArray,
    pub(super) vbo: glow017::Buffer,
    pub(super) empty_vao: glow017::VertexArray,
    pub(super) vertices: i32,
}

unsafe fn program(gl: &glow017::Context, vs: &str, fs: &str) -> glow017::Program {
    unsafe {
        let program = gl.create_program().expect("program");
        let mut shaders = Vec::new();
        for (kind, source) in [(glow017::VERTEX_SHADER, vs), (glow017::FRAGMENT_SHADER, fs)] {
            let shader = gl.create_shader(kind).expect("shader");
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            assert!(
                gl.get_shader_compile_status(shader),
                "{}",
                gl.get_shader_info_log(shader)
            );
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        gl.bind_frag_data_location(program, 0, "albedo");
        gl.bind_frag_data_location(program, 1, "normal");
        gl.link_program(program);
        assert!(
            gl.get_program_link_status(program),
            "{}",
            gl.get_program_info_log(program)
        );
        for shader in shaders {
            gl.detach_shader(program, shader);
            gl.delete_shader(shader);
        }
        program
    }
}

unsafe fn texture(
    gl: &glow017::Context,
    (width, height): (i32, i32),
    internal: u32,
    format: u32,
    ty: u32,
) -> glow017::Texture {
    unsafe {
        let t = gl.create_texture().expect("texture");
        gl.bind_texture(glow017::TEXTURE_2D, Some(t));
        gl.tex_parameter_i32(
            glow017::TEXTURE_2D,
            glow017::TEXTURE_MIN_FILTER,
            glow017::NEAREST as i32,
        );
        gl.tex_parameter_i32(
            glow017::TEXTURE_2D,
            glow017::TEXTURE_MAG_FILTER,
            glow017::NEAREST as i32,
        );
        gl.tex_image_2d(
            glow017::TEXTURE_2D,
            0,
            internal as i32,
            width,
            height,
            0,
            format,
            ty,
            glow017::PixelUnpackData::Slice(None),
        );
        gl.bind_texture(glow017::TEXTURE_2D, None);
        t
    }
}

impl Host017 {
    pub(super) fn new(gl: &glow017::Context, width: i32, height: i32) -> Host017 {
        unsafe {
            let size = (width, height);
            let albedo = texture(
                gl,
                size,
                glow017::RGBA8,
                glow017::RGBA,
                glow017::UNSIGNED_BYTE,
            );
            let normal = texture(
                gl,
                size,
                glow017::RGBA16F,
                glow017::RGBA,
                glow017::HALF_FLOAT,
            );
            let depth = texture(
                gl,
                size,
                glow017::DEPTH_COMPONENT24,
                glow017::DEPTH_COMPONENT,
                glow017::UNSIGNED_INT,
            );
            let lit = texture(
                gl,
                size,
                glow017::RGBA8,
                glow017::RGBA,
                glow017::UNSIGNED_BYTE,
            );
            let gbuffer = gl.create_framebuffer().expect("framebuffer");
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(gbuffer));
            for (point, t) in [
                (glow017::COLOR_ATTACHMENT0, albedo),
                (glow017::COLOR_ATTACHMENT1, normal),
                (glow017::DEPTH_ATTACHMENT, depth),
            ] {
                gl.framebuffer_texture_2d(
                    glow017::FRAMEBUFFER,
                    point,
                    glow017::TEXTURE_2D,
                    Some(t),
                    0,
                );
            }
            gl.draw_buffers(&[glow017::COLOR_ATTACHMENT0, glow017::COLOR_ATTACHMENT1]);
            assert_eq!(
                gl.check_framebuffer_status(glow017::FRAMEBUFFER),
                glow017::FRAMEBUFFER_COMPLETE
            );
            let lit_fbo = gl.create_framebuffer().expect("framebuffer");
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(lit_fbo));
            gl.framebuffer_texture_2d(
                glow017::FRAMEBUFFER,
                glow017::COLOR_ATTACHMENT0,
                glow017::TEXTURE_2D,
                Some(lit),
                0,
            );
            assert_eq!(
                gl.check_framebuffer_status(glow017::FRAMEBUFFER),
                glow017::FRAMEBUFFER_COMPLETE
            );
            gl.bind_framebuffer(glow017::FRAMEBUFFER, None);

            let geometry = program(gl, GEOMETRY_VS, GEOMETRY_FS);
            let lighting = program(gl, LIGHTING_VS, LIGHTING_FS);
            let data = scene();
            let vao = gl.create_vertex_array().expect("vertex array");
            let vbo = gl.create_buffer().expect("buffer");
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow017::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(
                glow017::ARRAY_BUFFER,
                bytemuck::cast_slice(&data),
                glow017::STATIC_DRAW,
            );
            for (name, offset) in [("position", 0), ("color", 12), ("normal", 24)] {
                let location = gl
                    .get_attrib_location(geometry, name)
                    .expect("attribute location");
                gl.enable_vertex_attrib_array(location);
                gl.vertex_attrib_pointer_f32(location, 3, glow017::FLOAT, false, 36, offset);
            }
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow017::ARRAY_BUFFER, None);
            let empty_vao = gl.create_vertex_array().expect("vertex array");
            Host017 {
                width,
                height,
                gbuffer,
                albedo,
                normal,
                depth,
                lit_fbo,
                lit,
                geometry,
                lighting,
                vao,
                vbo,
                empty_vao,
                vertices: (data.len() / 9) as i32,
            }
        }
    }

    /// The geometry pass into `target` (its G-buffer, or the retrofit's).
    pub(super) fn geometry_pass(&self, gl: &glow017::Context, target: glow017::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(target));
            gl.viewport(0, 0, self.width, self.height);
            gl.enable(glow017::DEPTH_TEST);
            gl.depth_func(glow017::LESS);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow017::COLOR_BUFFER_BIT | glow017::DEPTH_BUFFER_BIT);
            gl.use_program(Some(self.geometry));
            let location = gl.get_uniform_location(self.geometry, "projection");
            gl.uniform_matrix_4_f32_slice(location.as_ref(), false, &projection());
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow017::TRIANGLES, 0, self.vertices);
        }
    }

    /// The lighting pass into its lit framebuffer; the engine leaves its
    /// program, vertex array and G-buffer textures bound afterwards, on
    /// units 0 to 2, and unit 2 active, as engines do.
    pub(super) fn lighting_pass(&self, gl: &glow017::Context) {
        self.lighting_into(gl, self.lit_fbo);
    }

    /// The same lighting into `target` (the retrofit's own target for the
    /// second layer).
    pub(super) fn lighting_into(&self, gl: &glow017::Context, target: glow017::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow017::FRAMEBUFFER, Some(target));
            gl.viewport(0, 0, self.width, self.height);
            gl.disable(glow017::DEPTH_TEST);
            gl.use_program(Some(self.lighting));
            for (unit, (name, t)) in [
                ("g_albedo", self.albedo),
                ("g_normal", self.normal),
                ("g_depth", self.depth),
            ]
            .into_iter()
            .enumerate()
            {
                gl.active_texture(glow017::TEXTURE0 + unit as u32);
                gl.bind_texture(glow017::TEXTURE_2D, Some(t));
                let location = gl.get_uniform_location(self.lighting, name);
                gl.uniform_1_i32(location.as_ref(), unit as i32);
            }
            let location = gl.get_uniform_location(self.lighting, "light_dir");
            gl.uniform_3_f32(location.as_ref(), 0.4, 0.6, 0.7);
            gl.bind_vertex_array(Some(self.empty_vao));
            gl.draw_arrays(glow017::TRIANGLES, 0, 3);
        }
    }

    /// The lit image, top row first.
    pub(super) fn read_lit(&self, gl: &glow017::Context) -> RgbaImage {
        let mut bytes = vec![0u8; (self.width * self.height * 4) as usize];
        unsafe {
            gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, Some(self.lit_fbo));
            gl.read_buffer(glow017::COLOR_ATTACHMENT0);
            gl.pixel_store_i32(glow017::PACK_ALIGNMENT, 1);
            gl.read_pixels(
                0,
                0,
                self.width,
                self.height,
                glow017::RGBA,
                glow017::UNSIGNED_BYTE,
                glow017::PixelPackData::Slice(Some(&mut bytes)),
            );
            gl.pixel_store_i32(glow017::PACK_ALIGNMENT, 4);
            gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, None);
        }
        let (w, h) = (self.width as u32, self.height as u32);
        RgbaImage::from_fn(w, h, |x, y| {
            let i = (((h - 1 - y) * w + x) * 4) as usize;
            image::Rgba([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]])
        })
    }

    pub(super) fn destroy(self, gl: &glow017::Context) {
        unsafe {
            gl.use_program(None);
            gl.bind_vertex_array(None);
            gl.delete_framebuffer(self.gbuffer);
            gl.delete_framebuffer(self.lit_fbo);
            for t in [self.albedo, self.normal, self.depth, self.lit] {
                gl.delete_texture(t);
            }
            gl.delete_program(self.geometry);
            gl.delete_program(self.lighting);
            gl.delete_vertex_array(self.vao);
            gl.delete_vertex_array(self.empty_vao);
            gl.delete_buffer(self.vbo);
        }
    }
}

/// The host's own render at `scale` times the size, averaged back to
/// `W`x`H` (its lit values are linear: averaged as stored).
pub(super) fn host_image(gl: &glow017::Context, scale: i32) -> RgbaImage {
    let host = Host017::new(gl, W * scale, H * scale);
    host.geometry_pass(gl, host.gbuffer);
    host.lighting_pass(gl);
    let big = host.read_lit(gl);
    host.destroy(gl);
    let n = (scale * scale) as u32;
    let s = scale as u32;
    RgbaImage::from_fn(W as u32, H as u32, |x, y| {
        // In the light a screen emits for the engine's encoded values.
        let mut sum = [0f64; 4];
        for dy in 0..s {
            for dx in 0..s {
                let p = big.get_pixel(x * s + dx, y * s + dy);
                for c in 0..4 {
                    sum[c] += if c < 3 {
                        common::srgb::decode(p[c])
                    } else {
                        f64::from(p[c]) / 255.0
                    };
                }
            }
        }
        let mean = sum.map(|v| v / f64::from(n));
        image::Rgba([
            common::srgb::encode(mean[0]).round() as u8,
            common::srgb::encode(mean[1]).round() as u8,
            common::srgb::encode(mean[2]).round() as u8,
            (mean[3] * 255.0).round() as u8,
        ])
    })
}

/// The edge pixels of the host's own frame: a 4-neighbour whose linear
/// depth differs by more than 10 % (silhouettes and steps).
pub(super) fn edges(gl: &glow017::Context) -> image::GrayImage {
    let host = Host017::new(gl, W, H);
    host.geometry_pass(gl, host.gbuffer);
    let mut depth = vec![0f32; (W * H) as usize];
    unsafe {
        gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, Some(host.gbuffer));
        gl.read_pixels(
            0,
            0,
            W,
            H,
            glow017::DEPTH_COMPONENT,
            glow017::FLOAT,
            glow017::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut depth))),
        );
        gl.bind_framebuffer(glow017::READ_FRAMEBUFFER, None);
    }
    host.destroy(gl);
    let linear = |d: f32| {
        let z = 2.0 * d - 1.0;
        2.0 * NEAR * FAR / (FAR + NEAR - z * (FAR - NEAR))
    };
    let at = |x: i32, y: i32| linear(depth[((H - 1 - y) * W + x) as usize]);
    image::GrayImage::from_fn(W as u32, H as u32, |x, y| {
        let (x, y) = (x as i32, y as i32);
        let here = at(x, y);
        let step = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dx, dy)| {
            let (nx, ny) = (x + dx, y + dy);
            nx >= 0 && ny >= 0 && nx < W && ny < H && {
                let there = at(nx, ny);
                (here - there).abs() > 0.1 * here.min(there)
            }
        });
        image::Luma([if step { 255 } else { 0 }])
    })
}
