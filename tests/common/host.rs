//! A tiny host deferred renderer, written the way an engine would: its own
//! G-buffer FBO, its own model shader. Tests retrofit MSAA into it through
//! the public API alone.
#![allow(dead_code)]

use deferred_msaa_lab::gl::{
    Attachment, Buffer, Format, Framebuffer, Program, ShaderStage, Texture2d, TextureRef,
    VertexArray, preamble,
};
use glow::HasContext;

/// The host's model shader: it knows nothing of MSAA.
const HOST_VERT: &str = "
in vec3 a_position;
in vec3 a_color;
uniform mat4 u_projection;
out vec3 v_view;
out vec3 v_color;
void main() {
    v_view = a_position;
    v_color = a_color;
    gl_Position = u_projection * vec4(a_position, 1.0);
}
";
const HOST_FRAG: &str = "
in vec3 v_view;
in vec3 v_color;
out vec4 o_albedo;
out vec4 o_position;
out vec4 o_normal;
void main() {
    o_albedo = vec4(v_color, 1.0);
    o_position = vec4(v_view, 1.0);
    vec3 n = normalize(cross(dFdx(v_view), dFdy(v_view)));
    o_normal = vec4(n, 0.5);
}
";

/// A standard GL perspective matrix (column-major); `far = None` is infinite.
pub fn perspective(fov_y: f64, aspect: f64, near: f64, far: Option<f64>) -> [f64; 16] {
    let (p22, p23) = match far {
        Some(far) => ((far + near) / (near - far), 2.0 * far * near / (near - far)),
        None => (-1.0, -2.0 * near),
    };
    projection_matrix(fov_y, aspect, p22, p23)
}

/// Reversed-Z for `GL_ZERO_TO_ONE` depth: near → 1, far → 0; `far = None` is infinite.
pub fn perspective_reversed(fov_y: f64, aspect: f64, near: f64, far: Option<f64>) -> [f64; 16] {
    let (p22, p23) = match far {
        Some(far) => (near / (far - near), far * near / (far - near)),
        None => (0.0, near),
    };
    projection_matrix(fov_y, aspect, p22, p23)
}

/// A column-major perspective matrix with the given depth terms.
fn projection_matrix(fov_y: f64, aspect: f64, p22: f64, p23: f64) -> [f64; 16] {
    let f = 1.0 / (fov_y / 2.0).tan();
    let mut m = [0.0; 16];
    m[0] = f / aspect;
    m[5] = f;
    m[10] = p22;
    m[11] = -1.0;
    m[14] = p23;
    m
}

pub struct Host {
    pub albedo: Texture2d,
    pub position: Texture2d,
    pub normal: Texture2d,
    pub depth: Texture2d,
    pub fbo: Framebuffer,
    program: Program,
    vao: VertexArray,
    vbo: Option<Buffer>,
    vertices: i32,
    pub width: u32,
    pub height: u32,
}

impl Host {
    pub fn new(
        gl: &glow::Context,
        width: u32,
        height: u32,
        position: Format,
        depth: Format,
    ) -> Host {
        let albedo = Texture2d::new(gl, "host albedo", Format::Rgba16f, width, height).unwrap();
        let position = Texture2d::new(gl, "host position", position, width, height).unwrap();
        let normal = Texture2d::new(gl, "host normal", Format::Rgba16f, width, height).unwrap();
        let depth = Texture2d::new(gl, "host depth", depth, width, height).unwrap();
        let fbo = Framebuffer::new(
            gl,
            "host gbuffer",
            &[
                (Attachment::Color(0), TextureRef::from(&albedo)),
                (Attachment::Color(1), TextureRef::from(&position)),
                (Attachment::Color(2), TextureRef::from(&normal)),
                (
                    Attachment::for_depth_format(depth.format),
                    TextureRef::from(&depth),
                ),
            ],
            &[Some(0), Some(1), Some(2)],
        )
        .unwrap();
        let program = Program::build(
            gl,
            "host model",
            &preamble(&[], &[]),
            &[
                (ShaderStage::Vertex, "host.vert", HOST_VERT),
                (ShaderStage::Fragment, "host.frag", HOST_FRAG),
            ],
            &[("o_albedo", 0), ("o_position", 1), ("o_normal", 2)],
        )
        .unwrap();
        let vao = VertexArray::new(gl, "host vao").unwrap();
        Host {
            albedo,
            position,
            normal,
            depth,
            fbo,
            program,
            vao,
            vbo: None,
            vertices: 0,
            width,
            height,
        }
    }

    /// Upload triangles: per vertex a view-space position and a colour.
    pub fn set_triangles(&mut self, gl: &glow::Context, data: &[f32]) {
        if let Some(old) = self.vbo.take() {
            old.destroy(gl);
        }
        let vbo = Buffer::with_data(
            gl,
            "host vertices",
            glow::ARRAY_BUFFER,
            bytemuck::cast_slice(data),
            glow::STATIC_DRAW,
        )
        .unwrap();
        unsafe {
            self.vao.bind(gl);
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo.raw()));
            let pos = gl
                .get_attrib_location(self.program.raw(), "a_position")
                .unwrap();
            let col = gl
                .get_attrib_location(self.program.raw(), "a_color")
                .unwrap();
            gl.enable_vertex_attrib_array(pos);
            gl.vertex_attrib_pointer_f32(pos, 3, glow::FLOAT, false, 24, 0);
            gl.enable_vertex_attrib_array(col);
            gl.vertex_attrib_pointer_f32(col, 3, glow::FLOAT, false, 24, 12);
            gl.bind_vertex_array(None);
        }
        self.vbo = Some(vbo);
        self.vertices = (data.len() / 6) as i32;
    }

    /// The host's geometry pass into whatever framebuffer is bound.
    /// `reversed`: clear to 0 and keep the greater depth.
    pub fn draw(&self, gl: &glow::Context, projection: &[f64; 16], reversed: bool) {
        let m: Vec<f32> = projection.iter().map(|&v| v as f32).collect();
        let m: [f32; 16] = m.try_into().unwrap();
        unsafe {
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(if reversed { glow::GREATER } else { glow::LESS });
            gl.depth_mask(true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(if reversed { 0.0 } else { 1.0 });
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            self.program.bind(gl);
            self.program.set_mat4(gl, "u_projection", &m);
            self.vao.bind(gl);
            gl.draw_arrays(glow::TRIANGLES, 0, self.vertices);
            gl.bind_vertex_array(None);
        }
    }

    pub fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        for t in [self.albedo, self.position, self.normal, self.depth] {
            t.destroy(gl);
        }
        self.program.destroy(gl);
        self.vao.destroy(gl);
        if let Some(b) = self.vbo {
            b.destroy(gl);
        }
    }
}

/// Append one triangle (view-space corners, one colour).
pub fn triangle(out: &mut Vec<f32>, corners: [[f32; 3]; 3], colour: [f32; 3]) {
    for c in corners {
        out.extend_from_slice(&c);
        out.extend_from_slice(&colour);
    }
}

/// The frame the resolve is given for a draw with `projection`: the matrix
/// as the host uploads it (f32), in standard or reversed-Z depth.
pub fn frame(projection: &[f64; 16], reversed: bool) -> deferred_msaa::Frame {
    let mode = if reversed {
        deferred_msaa::DepthMode::ReversedZ
    } else {
        deferred_msaa::DepthMode::Standard
    };
    deferred_msaa::Frame::from_matrix(projection.map(|v| v as f32)).with_depth_mode(mode)
}
