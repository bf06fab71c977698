//! The host's geometry pass (a back face over the whole image, a front
//! triangle with a sub-pixel side face), its planes read back, and the
//! comparison with the host's own render.

use deferred_msaa_testkit::Rng;
use deferred_msaa_testkit::random_host::{DepthPoint, RandomHost, ValueKind};
use glow::HasContext;

/// One image of the host's framebuffer read back: 4 values a pixel (or 1
/// for depth and stencil), as bytes.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Plane {
    pub(super) name: String,
    /// Bytes per pixel.
    pub(super) bpp: usize,
    pub(super) raw: Vec<u8>,
    /// Whether the resolve selects one sample of it (integer, stencil).
    pub(super) selected: bool,
    /// Whether the geometry pass writes it.
    pub(super) drawn: bool,
    /// How far a 32-bit unsigned normalised depth may move: the resolve
    /// writes depth through `gl_FragDepth`, a float of 24 bits, so the
    /// 32-bit value comes back within one float step of its own, never bit
    /// for bit (0 for every other plane: exact).
    pub(super) slack: f32,
}

impl Plane {
    pub(super) fn texel(&self, i: usize) -> &[u8] {
        &self.raw[i * self.bpp..(i + 1) * self.bpp]
    }

    /// Pixel `i` of `other` holds this plane's value at pixel `j`.
    pub(super) fn same(&self, j: usize, other: &Plane, i: usize) -> bool {
        let (a, b) = (self.texel(j), other.texel(i));
        if self.slack == 0.0 {
            return a == b;
        }
        let f = |t: &[u8]| f32::from_ne_bytes([t[0], t[1], t[2], t[3]]);
        (f(a) - f(b)).abs() <= self.slack
    }
}

/// The geometry pass of a random host: two faces of constant values.
pub(super) struct Geometry {
    pub(super) program: glow::Program,
    pub(super) vao: glow::VertexArray,
    pub(super) vbo: glow::Buffer,
    face: Option<glow::UniformLocation>,
    /// The front triangle in window coordinates of a unit square ((0,0)
    /// bottom left, (1,1) top right).
    triangle: [[f32; 2]; 3],
}

/// How far the front triangle's side face reaches out from its first edge,
/// in pixels: a sliver that a pixel's samples meet now and then, so that
/// pixels of three surfaces (the front face, its side, the back face) occur
/// as a thin box's silhouette has them.
pub(super) const SIDE_PX: f32 = 0.35;

/// The value a face writes to attachment `k` (as a GLSL expression).
pub(super) fn face_value(seed: u64, k: usize, face: u32, kind: ValueKind) -> String {
    let mut rng = Rng::new(seed.wrapping_mul(1_000_003) ^ (k as u64 * 131 + face as u64 * 7 + 1));
    let mut v = [0f32; 4];
    let mut i = [0i64; 4];
    for c in 0..4 {
        v[c] = match kind {
            ValueKind::Unorm => rng.unit(),
            ValueKind::Snorm => rng.range(-1.0, 1.0),
            ValueKind::Float { unsigned: true } => rng.range(0.0, 8.0),
            _ => rng.range(-8.0, 8.0),
        };
        // Small enough for every integer format (RGB10_A2UI's alpha has 2 bits).
        i[c] = match kind {
            ValueKind::Int if c == 3 => rng.below(3) as i64 - 1,
            ValueKind::Int => rng.below(81) as i64 - 40,
            _ if c == 3 => rng.below(4) as i64,
            _ => rng.below(81) as i64,
        };
    }
    match kind {
        ValueKind::Int => format!("ivec4({}, {}, {}, {})", i[0], i[1], i[2], i[3]),
        ValueKind::Uint => format!("uvec4({}u, {}u, {}u, {}u)", i[0], i[1], i[2], i[3]),
        _ => format!("vec4({:.8}, {:.8}, {:.8}, {:.8})", v[0], v[1], v[2], v[3]),
    }
}

pub(super) const VERTEX: &str = "#version 150
in vec3 position;
void main() { gl_Position = vec4(position, 1.0); }
";

impl Geometry {
    pub(super) fn new(gl: &glow::Context, host: &RandomHost) -> Geometry {
        let spec = &host.spec;
        let mut decls = String::new();
        let mut writes = [String::new(), String::new()];
        let mut outputs = Vec::new();
        for (i, b) in spec.draw_buffers.iter().enumerate() {
            let Some(point) = b else { continue };
            let k = spec.colors.iter().position(|c| c.point == *point).unwrap();
            let kind = host.kinds[k];
            let ty = match kind {
                ValueKind::Int => "ivec4",
                ValueKind::Uint => "uvec4",
                _ => "vec4",
            };
            decls += &format!("out {ty} o{i};\n");
            for face in 0..2 {
                writes[face as usize] +=
                    &format!("    o{i} = {};\n", face_value(spec.seed, k, face, kind));
            }
            outputs.push((i as u32, format!("o{i}")));
        }
        let fragment = format!(
            "#version 150\nuniform int face;\n{decls}void main() {{\n  if (face == 0) {{\n{}  }} else {{\n{}  }}\n}}\n",
            writes[0], writes[1]
        );
        let mut rng = Rng::new(spec.seed ^ 0x5eed_face);
        let triangle = [
            [rng.range(0.05, 0.45), rng.range(0.05, 0.45)],
            [rng.range(0.55, 0.95), rng.range(0.1, 0.6)],
            [rng.range(0.2, 0.8), rng.range(0.6, 0.95)],
        ];
        let ndc = |p: [f32; 2]| [p[0] * 2.0 - 1.0, p[1] * 2.0 - 1.0];
        let mut vertices: Vec<f32> = Vec::new();
        // The back face: the whole image, two triangles, at depth 0.5.
        for p in [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]] {
            vertices.extend([p[0], p[1], 0.5]);
        }
        for p in triangle {
            let q = ndc(p);
            vertices.extend([q[0], q[1], -0.25]);
        }
        // The side face: a quad along the first edge, receding from the
        // front face's depth outwards by SIDE_PX pixels. It writes the front
        // face's values (one object's material), at other depths.
        // At the larger of the host's two sizes (it is resized once): no
        // wider than SIDE_PX at either.
        let w = host.width.max(spec.resized.0) as f32;
        let h = host.height.max(spec.resized.1) as f32;
        let centre = [0, 1].map(|c| (triangle[0][c] + triangle[1][c] + triangle[2][c]) / 3.0);
        let (a, b) = (triangle[0], triangle[1]);
        let (dx, dy) = ((b[0] - a[0]) * w, (b[1] - a[1]) * h);
        let len = (dx * dx + dy * dy).sqrt().max(1e-6);
        let mut out = [dy / len, -dx / len];
        let away = [(a[0] - centre[0]) * w, (a[1] - centre[1]) * h];
        if out[0] * away[0] + out[1] * away[1] < 0.0 {
            out = [-out[0], -out[1]];
        }
        let shifted = |p: [f32; 2]| [p[0] + out[0] * SIDE_PX / w, p[1] + out[1] * SIDE_PX / h];
        let side = [(a, -0.25), (b, -0.25), (shifted(b), -0.15)];
        let side2 = [(a, -0.25), (shifted(b), -0.15), (shifted(a), -0.15)];
        for (p, z) in side.into_iter().chain(side2) {
            let q = ndc(p);
            vertices.extend([q[0], q[1], z]);
        }
        unsafe {
            let program = gl.create_program().unwrap();
            let mut shaders = Vec::new();
            for (stage, source) in [
                (glow::VERTEX_SHADER, VERTEX),
                (glow::FRAGMENT_SHADER, fragment.as_str()),
            ] {
                let shader = gl.create_shader(stage).unwrap();
                gl.shader_source(shader, source);
                gl.compile_shader(shader);
                assert!(
                    gl.get_shader_compile_status(shader),
                    "{}\n{source}",
                    gl.get_shader_info_log(shader)
                );
                gl.attach_shader(program, shader);
                shaders.push(shader);
            }
            gl.bind_attrib_location(program, 0, "position");
            for (i, name) in &outputs {
                gl.bind_frag_data_location(program, *i, name);
            }
            gl.link_program(program);
            assert!(
                gl.get_program_link_status(program),
                "{}",
                gl.get_program_info_log(program)
            );
            for s in shaders {
                gl.detach_shader(program, s);
                gl.delete_shader(s);
            }
            let vao = gl.create_vertex_array().unwrap();
            let vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&vertices),
                glow::STATIC_DRAW,
            );
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 12, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            let face = gl.get_uniform_location(program, "face");
            Geometry {
                program,
                vao,
                vbo,
                face,
                triangle,
            }
        }
    }

    /// The host's geometry pass into `fbo`, with the state it sets itself.
    pub(super) fn draw(&self, gl: &glow::Context, host: &RandomHost, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, host.width as i32, host.height as i32);
            for cap in [
                glow::SCISSOR_TEST,
                glow::BLEND,
                glow::CULL_FACE,
                glow::RASTERIZER_DISCARD,
                glow::SAMPLE_MASK,
                glow::POLYGON_OFFSET_FILL,
                glow::FRAMEBUFFER_SRGB,
                glow::SAMPLE_ALPHA_TO_COVERAGE,
                glow::SAMPLE_ALPHA_TO_ONE,
            ] {
                gl.disable(cap);
            }
            gl.enable(glow::MULTISAMPLE);
            gl.polygon_mode(glow::FRONT_AND_BACK, glow::FILL);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.clear_depth_f64(1.0);
            gl.clear_stencil(0);
            gl.clear(glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
            gl.use_program(Some(self.program));
            gl.bind_vertex_array(Some(self.vao));
            // The back face, then the front triangle with its side face.
            for (face, reference, first, count) in [(0, 0x5A, 0, 3), (1, 0xA5, 3, 9)] {
                gl.stencil_func(glow::ALWAYS, reference, 0xFF);
                gl.uniform_1_i32(self.face.as_ref(), face);
                gl.draw_arrays(glow::TRIANGLES, first, count);
            }
            gl.disable(glow::STENCIL_TEST);
        }
    }

    /// Which face pixel `(x, y)` of a `w` x `h` image lies wholly inside
    /// (0 the back, 1 the front triangle), or `None` on an edge.
    pub(super) fn face_of(&self, x: u32, y: u32, w: u32, h: u32) -> Option<u32> {
        let c = [x as f32 + 0.5, y as f32 + 0.5];
        let t = self.triangle.map(|p| [p[0] * w as f32, p[1] * h as f32]);
        // Signed distances to the three edges (positive inside, for a
        // counter-clockwise triangle; the sign is fixed by the winding).
        let area =
            (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
        let sign = area.signum();
        let mut min = f32::INFINITY;
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = (dx * dx + dy * dy).sqrt().max(1e-6);
            let d = sign * (dx * (c[1] - a[1]) - dy * (c[0] - a[0])) / len;
            min = min.min(d);
        }
        // Half a pixel's diagonal, with room for rounding, and the side
        // face beyond the first edge.
        let margin = 0.75 + SIDE_PX;
        if min > margin {
            Some(1)
        } else if min < -margin {
            Some(0)
        } else {
            None
        }
    }

    pub(super) fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_program(self.program);
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.vbo);
        }
    }
}

/// Every image of the host's framebuffer, read back.
pub(super) fn read_planes(gl: &glow::Context, host: &RandomHost) -> Vec<Plane> {
    let spec = &host.spec;
    let n = (host.width * host.height) as usize;
    let mut planes = Vec::new();
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(host.fbo));
        gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.pixel_store_i32(glow::PACK_ROW_LENGTH, 0);
        let read = |name: String, format: u32, ty: u32, bpp: usize, selected, drawn| {
            let mut raw = vec![0u8; n * bpp];
            gl.read_pixels(
                0,
                0,
                host.width as i32,
                host.height as i32,
                format,
                ty,
                glow::PixelPackData::Slice(Some(&mut raw)),
            );
            Plane {
                name,
                bpp,
                raw,
                selected,
                drawn,
                slack: 0.0,
            }
        };
        for (c, kind) in spec.colors.iter().zip(&host.kinds) {
            gl.read_buffer(glow::COLOR_ATTACHMENT0 + c.point);
            let (format, ty) = match kind {
                ValueKind::Int => (glow::RGBA_INTEGER, glow::INT),
                ValueKind::Uint => (glow::RGBA_INTEGER, glow::UNSIGNED_INT),
                _ => (glow::RGBA, glow::FLOAT),
            };
            planes.push(read(
                format!("GL_COLOR_ATTACHMENT{} ({})", c.point, c.format.name),
                format,
                ty,
                16,
                kind.is_integer(),
                spec.draw_buffers.contains(&Some(c.point)),
            ));
        }
        if let Some(d) = &spec.depth {
            if d.point != DepthPoint::Stencil {
                planes.push(read(
                    format!("depth ({})", d.format.name),
                    glow::DEPTH_COMPONENT,
                    glow::FLOAT,
                    4,
                    false,
                    true,
                ));
                let p = |pname| {
                    gl.get_framebuffer_attachment_parameter_i32(
                        glow::READ_FRAMEBUFFER,
                        glow::DEPTH_ATTACHMENT,
                        pname,
                    )
                };
                if p(glow::FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE) == 32
                    && p(glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE)
                        == glow::UNSIGNED_NORMALIZED as i32
                {
                    if let Some(depth) = planes.last_mut() {
                        depth.slack = f32::EPSILON;
                    }
                }
            }
        }
        if spec.has_stencil() {
            planes.push(read(
                "stencil".into(),
                glow::STENCIL_INDEX,
                glow::UNSIGNED_BYTE,
                1,
                true,
                true,
            ));
        }
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    }
    planes
}

/// Compare the retrofit's planes with the host's own render.
pub(super) fn compare(
    what: &str,
    geometry: &Geometry,
    host: &RandomHost,
    reference: &[Plane],
    got: &[Plane],
    failures: &mut Vec<String>,
) {
    let (w, h) = (host.width, host.height);
    let faces: Vec<Option<u32>> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| geometry.face_of(x, y, w, h))
        .collect();
    for (r, g) in reference.iter().zip(got) {
        // The value each face has wholly inside it, for the edges' check.
        let inside: Vec<Option<&[u8]>> = (0..2)
            .map(|f| faces.iter().position(|&p| p == Some(f)).map(|i| r.texel(i)))
            .collect();
        let mut bad = 0;
        let mut first = None;
        for (i, face) in faces.iter().enumerate() {
            let ok = if !r.drawn || face.is_some() {
                r.same(i, g, i)
            } else if r.selected {
                // On an edge a selected value is one sample's: one face's.
                match (inside[0], inside[1]) {
                    (Some(a), Some(b)) => g.texel(i) == a || g.texel(i) == b,
                    _ => true,
                }
            } else {
                true
            };
            if !ok {
                bad += 1;
                first.get_or_insert(i);
            }
        }
        if let Some(i) = first {
            let rule = if !r.drawn {
                "untouched"
            } else if faces[i].is_some() {
                "bit for bit inside a face"
            } else {
                "one face's value at an edge"
            };
            failures.push(format!(
                "{what}: {}: {bad} pixels not {rule}; first at ({}, {}): host {:?}, retrofit {:?}",
                r.name,
                i as u32 % w,
                i as u32 / w,
                r.texel(i),
                g.texel(i)
            ));
        }
    }
}
