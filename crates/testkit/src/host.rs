//! The toy host: a tiny deferred renderer written the way an engine would
//! write one, with its own G-buffer textures and FBO, its own model shader
//! and its own lighting pass, none of which knows anything of MSAA. The tests and the resolve benches
//! retrofit MSAA into it through the public API alone.

use deferred_msaa::Result;
use deferred_msaa::gl::{
    Attachment, Buffer, Format, Framebuffer, FullscreenPass, Made, Program, ShaderSource,
    ShaderStage, Texture2d, TextureRef, VertexArray, draw_fullscreen_triangle, preamble,
};
use glow::HasContext;

/// The model shader's vertex stage: view-space positions in.
const MODEL_VERT: &str = "
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

/// The model shader's fragment stage: the outputs the G-buffer has, each
/// behind its define. Specular is 8-bit-friendly; emission reaches HDR
/// values, so that an HDR blend is exercised.
const MODEL_FRAG: &str = "
in vec3 v_view;
in vec3 v_color;
#ifdef OUT_COLOR
out vec4 o_color;
#endif
#ifdef OUT_POSITION
out vec4 o_position;
#endif
#ifdef OUT_NORMAL
out vec4 o_normal;
#endif
#ifdef OUT_SPECULAR
out vec4 o_specular;
#endif
#ifdef OUT_EMISSIVE
out vec4 o_emissive;
#endif
#ifdef OUT_MATERIAL
out vec4 o_material;
#endif
#ifdef OUT_LINEAR_DEPTH
out vec4 o_linear_depth;
#endif
#ifdef OUT_TINT
out vec4 o_tint;
#endif
void main() {
#ifdef OUT_COLOR
    o_color = vec4(v_color, 1.0);
#endif
#ifdef OUT_POSITION
    o_position = vec4(v_view, 1.0);
#endif
#ifdef OUT_NORMAL
    o_normal = vec4(normalize(cross(dFdx(v_view), dFdy(v_view))), 0.5);
#endif
#ifdef OUT_SPECULAR
    o_specular = vec4(v_color.bgr, 0.25);
#endif
#ifdef OUT_EMISSIVE
    o_emissive = vec4(v_color * (40.0 * v_color.r * v_color.r), 1.0);
#endif
#ifdef OUT_MATERIAL
    o_material = vec4(v_color.gbr * 0.5, 0.75);
#endif
#ifdef OUT_LINEAR_DEPTH
    o_linear_depth = vec4(-v_view.z, 0.0, 0.0, 1.0);
#endif
#ifdef OUT_TINT
    o_tint = vec4(v_color.rrg, 0.125);
#endif
}
";

/// The host's lighting: its colour attachment times a gain (an HDR value
/// for a gain above 1), where anything was drawn, onto whatever the output
/// held. Per pixel, as deferred lighting is.
const LIGHTING_FRAG: &str = "
uniform sampler2D u_color;
uniform float u_gain;
out vec4 o_color;
void main() {
    vec4 c = texelFetch(u_color, ivec2(gl_FragCoord.xy), 0);
    o_color = vec4(c.rgb * u_gain, c.a);
}
";

/// One output of the host's model shader, a colour attachment of its G-buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// The vertex colour, alpha 1.
    Color,
    /// The view-space position, w 1.
    Position,
    /// The face normal, w 0.5.
    Normal,
    /// The colour's `bgr`, w 0.25.
    Specular,
    /// Emission up to 40× the colour.
    Emissive,
    /// The colour's `gbr` halved, w 0.75 (an engine's material bytes).
    Material,
    /// The view-space distance `-z` in red (an engine's linear depth).
    LinearDepth,
    /// The colour's `rrg`, w 0.125.
    Tint,
}

impl Output {
    /// Every output, in the order FreeSpace Open's G-buffer has them.
    pub const ALL: [Output; 5] = [
        Output::Color,
        Output::Position,
        Output::Normal,
        Output::Specular,
        Output::Emissive,
    ];

    /// Three more, for wide G-buffers (engines with six to eight colour
    /// attachments).
    pub const WIDE: [Output; 3] = [Output::Material, Output::LinearDepth, Output::Tint];

    /// The name a G-buffer layout gives the attachment (`color`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Output::Color => "color",
            Output::Position => "position",
            Output::Normal => "normal",
            Output::Specular => "specular",
            Output::Emissive => "emissive",
            Output::Material => "material",
            Output::LinearDepth => "linear_depth",
            Output::Tint => "tint",
        }
    }

    /// The output named `name`, if the shader has it.
    pub fn from_name(name: &str) -> Option<Output> {
        Output::ALL
            .into_iter()
            .chain(Output::WIDE)
            .find(|o| o.name() == name)
    }
}

/// The toy host: its G-buffer (textures, FBO), its model program and its
/// vertices.
#[derive(Debug)]
pub struct Host {
    /// The colour attachments, in attachment order, with what each holds.
    pub colors: Vec<(Output, Texture2d)>,
    /// The depth attachment.
    pub depth: Texture2d,
    /// The G-buffer framebuffer (all colour attachments drawn).
    pub fbo: Framebuffer,
    program: Program,
    vao: VertexArray,
    lighting: FullscreenPass,
    empty: VertexArray,
    vbo: Option<Buffer>,
    vertices: i32,
    /// The image size.
    pub width: u32,
    /// The image size.
    pub height: u32,
}

impl Host {
    /// A host whose G-buffer is `outputs` (attachments 0, 1, ...) and a
    /// `depth` attachment, of `width` × `height`.
    pub fn with_outputs(
        gl: &glow::Context,
        width: u32,
        height: u32,
        outputs: &[(Output, Format)],
        depth: Format,
    ) -> Result<Host> {
        Made::build(gl, |made| {
            let mut colors = Vec::with_capacity(outputs.len());
            for &(output, format) in outputs {
                let label = format!("host {}", output.name());
                let texture = made.keep(Texture2d::new(gl, &label, format, width, height)?);
                colors.push((output, texture));
            }
            let depth = made.keep(Texture2d::new(gl, "host depth", depth, width, height)?);
            let mut attachments: Vec<(Attachment, TextureRef)> = colors
                .iter()
                .enumerate()
                .map(|(k, (_, t))| (Attachment::Color(k as u32), TextureRef::from(t)))
                .collect();
            attachments.push((
                Attachment::for_depth_format(depth.format),
                TextureRef::from(&depth),
            ));
            let draw: Vec<Option<u32>> = (0..colors.len() as u32).map(Some).collect();
            let fbo = made.keep(Framebuffer::new(gl, "host gbuffer", &attachments, &draw)?);
            let names: Vec<String> = outputs
                .iter()
                .map(|(o, _)| format!("o_{}", o.name()))
                .collect();
            let locations: Vec<(&str, u32)> = names
                .iter()
                .enumerate()
                .map(|(k, n)| (n.as_str(), k as u32))
                .collect();
            let defines: Vec<(String, String)> = outputs
                .iter()
                .map(|(o, _)| (format!("OUT_{}", o.name().to_uppercase()), "1".into()))
                .collect();
            let program = made.keep(Program::build(
                gl,
                "host model",
                &preamble(&[], &defines),
                &[
                    (ShaderStage::Vertex, "host.vert", MODEL_VERT),
                    (ShaderStage::Fragment, "host.frag", MODEL_FRAG),
                ],
                &locations,
            )?);
            let vao = made.keep(VertexArray::new(gl, "host vao")?);
            let lighting = made.keep(FullscreenPass::new(
                gl,
                "host lighting",
                &ShaderSource::new().part("host lighting.frag", LIGHTING_FRAG),
                &[("o_color", 0)],
            )?);
            let empty = made.keep(VertexArray::new(gl, "host full-screen triangle")?);
            Ok(Host {
                colors,
                depth,
                fbo,
                program,
                vao,
                lighting,
                empty,
                vbo: None,
                vertices: 0,
                width,
                height,
            })
        })
    }

    /// The tests' usual host: RGBA16F colour, a view-space position of
    /// `position`'s format, an RGBA16F normal, and `depth`.
    pub fn new(
        gl: &glow::Context,
        width: u32,
        height: u32,
        position: Format,
        depth: Format,
    ) -> Result<Host> {
        let outputs = [
            (Output::Color, Format::Rgba16f),
            (Output::Position, position),
            (Output::Normal, Format::Rgba16f),
        ];
        Host::with_outputs(gl, width, height, &outputs, depth)
    }

    /// The attachment holding `output`, if the G-buffer has it.
    pub fn texture(&self, output: Output) -> Option<&Texture2d> {
        self.colors
            .iter()
            .find(|(o, _)| *o == output)
            .map(|(_, t)| t)
    }

    /// The colour attachment. Panics when the host has none: a test kit
    /// host is built with what its test reads.
    pub fn color(&self) -> &Texture2d {
        self.expect(Output::Color)
    }

    /// The position attachment (panics without one, as [`Host::color`]).
    pub fn position(&self) -> &Texture2d {
        self.expect(Output::Position)
    }

    /// The normal attachment (panics without one, as [`Host::color`]).
    pub fn normal(&self) -> &Texture2d {
        self.expect(Output::Normal)
    }

    fn expect(&self, output: Output) -> &Texture2d {
        match self.texture(output) {
            Some(t) => t,
            None => panic!("the host has no {} attachment", output.name()),
        }
    }

    /// Upload triangles (see [`scene`](crate::scene)), replacing any before.
    pub fn set_triangles(&mut self, gl: &glow::Context, data: &[f32]) -> Result<()> {
        let vbo = Buffer::with_data(
            gl,
            "host vertices",
            glow::ARRAY_BUFFER,
            bytemuck::cast_slice(data),
            glow::STATIC_DRAW,
        )?;
        // Attribute locations are the linker's, so they are asked for.
        unsafe {
            self.vao.bind(gl);
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo.raw()));
            for (name, offset) in [("a_position", 0), ("a_color", 12)] {
                if let Some(loc) = gl.get_attrib_location(self.program.raw(), name) {
                    gl.enable_vertex_attrib_array(loc);
                    gl.vertex_attrib_pointer_f32(loc, 3, glow::FLOAT, false, 24, offset);
                }
            }
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
        }
        if let Some(old) = self.vbo.replace(vbo) {
            old.destroy(gl);
        }
        self.vertices = (data.len() / 6) as i32;
        Ok(())
    }

    /// The host's geometry pass into whatever framebuffer is bound: clear,
    /// then the triangles with `projection`. `reversed`: clear depth to 0
    /// and keep the greater depth.
    pub fn draw(&self, gl: &glow::Context, projection: &[f64; 16], reversed: bool) {
        unsafe {
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.depth_mask(true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(if reversed { 0.0 } else { 1.0 });
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
        }
        self.draw_without_clear(gl, projection, reversed);
    }

    /// [`Host::draw`] without its clear, for an engine that clears its
    /// G-buffer elsewhere (through another framebuffer sharing its
    /// textures, or per attachment with values of its own).
    pub fn draw_without_clear(&self, gl: &glow::Context, projection: &[f64; 16], reversed: bool) {
        let m = crate::projection::to_f32(projection);
        unsafe {
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(if reversed { glow::GREATER } else { glow::LESS });
            gl.depth_mask(true);
            self.program.bind(gl);
            self.program.set_mat4(gl, "u_projection", &m);
            self.vao.bind(gl);
            gl.draw_arrays(glow::TRIANGLES, 0, self.vertices);
            gl.bind_vertex_array(None);
            gl.use_program(None);
        }
    }

    /// The host's lighting pass into `output` (its draw buffer 0): the
    /// colour attachment times `gain`, per pixel. Needs a colour output.
    pub fn light(&self, gl: &glow::Context, output: glow::Framebuffer, gain: f32) {
        let program = self.lighting.program();
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(output));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(self.color().raw()));
        }
        program.bind(gl);
        program.set_i32(gl, "u_color", 0);
        program.set_f32(gl, "u_gain", gain);
        draw_fullscreen_triangle(gl, &self.empty);
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.use_program(None);
        }
    }

    /// Free every GL object the host made.
    pub fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        for (_, t) in self.colors {
            t.destroy(gl);
        }
        self.depth.destroy(gl);
        self.program.destroy(gl);
        self.vao.destroy(gl);
        self.lighting.destroy(gl);
        self.empty.destroy(gl);
        if let Some(b) = self.vbo {
            b.destroy(gl);
        }
    }
}
