//! Drawing a view into the window: the final image, a G-buffer attachment,
//! the depth or the complex pixels.

use std::error::Error;

use deferred_msaa_lab::gl::{
    FullscreenPass, Made, ShaderSource, VertexArray, check_error, draw_fullscreen_triangle,
};
use deferred_msaa_lab::renderer::Renderer;
use deferred_msaa_lab::resolve::{
    COMPLEX_GLSL, COMPLEX_GLSL_NAME, DepthProjection, KeySource, ResolveSlot,
};
use glow::HasContext;
use winit::dpi::PhysicalSize;

type AnyResult<T> = Result<T, Box<dyn Error>>;

/// What is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum View {
    /// The final image.
    Final,
    /// Colour attachment `k` of the resolved G-buffer.
    Attachment(usize),
    /// The resolved depth, linearised.
    Depth,
    /// Pixels whose samples differ in depth (the ones the resolve blends).
    Complex,
}

// ---------------------------------------------------------------------------
// Drawing a view into the window.

/// One texel of the chosen texture per window pixel, made readable.
pub(crate) const PRESENT_FRAG: &str = r#"
uniform sampler2D u_image;
uniform vec2 u_window;
uniform int u_mode;       // 0 as is, 1 linear colour, 2 position, 3 normal, 4 HDR, 5 depth
uniform vec4 u_depth;     // p22, p23, zero_to_one, clear depth
uniform vec2 u_range;     // view distances mapped to white .. dark grey
out vec4 o_color;

vec3 srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

// Near: warm white, far: dark blue, with a soft band every 1/6 of the range.
vec3 ramp(float dist) {
    float t = clamp((dist - u_range.x) / max(u_range.y - u_range.x, 1e-6), 0.0, 1.0);
    float contour = 0.85 + 0.15 * cos(6.2831853 * 6.0 * t);
    return mix(vec3(1.0, 0.9, 0.7), vec3(0.05, 0.1, 0.4), sqrt(t)) * contour;
}

void main() {
    ivec2 size = textureSize(u_image, 0);
    ivec2 p = clamp(ivec2(gl_FragCoord.xy * vec2(size) / u_window), ivec2(0), size - 1);
    vec4 t = texelFetch(u_image, p, 0);
    vec3 c = t.rgb;
    if (u_mode == 1) {
        c = srgb(t.rgb);
    } else if (u_mode == 2) {
        c = t.w == 0.0 ? vec3(0.0) : ramp(-t.z);
    } else if (u_mode == 3) {
        c = dot(t.xyz, t.xyz) < 0.25 ? vec3(0.0) : normalize(t.xyz) * 0.5 + 0.5;
    } else if (u_mode == 4) {
        vec3 x = max(mix(t.rgb, vec3(0.0), isnan(t.rgb)), vec3(0.0));
        c = srgb(x / (1.0 + x));
    } else if (u_mode == 5) {
        float d = t.r;
        float z_ndc = u_depth.z > 0.5 ? d : 2.0 * d - 1.0;
        c = d == u_depth.w ? vec3(0.0) : ramp(u_depth.y / (z_ndc + u_depth.x));
    }
    o_color = vec4(c, 1.0);
}
"#;

/// The final image in grey, with the pixels whose samples differ in their
/// depth key in orange: where the resolve has work to do. It follows
/// `complex.glsl` ([`COMPLEX_GLSL`]), composed in front of it.
pub(crate) const COMPLEX_FRAG: &str = r#"
uniform sampler2D u_image;
uniform sampler2DMS u_key;
uniform int u_samples;
uniform int u_component;  // 0: depth (r), 2: view-space position (z)
uniform vec2 u_window;
out vec4 o_color;

float key(ivec2 p, int i) {
    vec4 v = texelFetch(u_key, p, i);
    return u_component == 0 ? v.r : v.z;
}

void main() {
    ivec2 size = textureSize(u_image, 0);
    ivec2 p = clamp(ivec2(gl_FragCoord.xy * vec2(size) / u_window), ivec2(0), size - 1);
    bool complex = false;
    float first = key(p, 0);
    for (int i = 1; i < u_samples; ++i) {
        // No depth samples here to tell background by (with a position key),
        // so every sample counts as geometry: the view stays as it was.
        complex = complex || !dmsaa_same_surface(false, key(p, i), false, first);
    }
    vec3 c = texelFetch(u_image, p, 0).rgb;
    float grey = dot(c, vec3(0.299, 0.587, 0.114)) * 0.7;
    o_color = vec4(complex ? vec3(1.0, 0.45, 0.05) : vec3(grey), 1.0);
}
"#;

pub(crate) struct Presenter {
    pub(crate) view: FullscreenPass,
    pub(crate) complex: FullscreenPass,
    pub(crate) vao: VertexArray,
}

impl Presenter {
    pub(crate) fn new(gl: &glow::Context) -> AnyResult<Presenter> {
        let present = ShaderSource::new().part("viewer present.frag", PRESENT_FRAG);
        let complex = ShaderSource::new()
            .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
            .part("viewer complex.frag", COMPLEX_FRAG);
        let outputs = [("o_color", 0)];
        let presenter = Made::build(gl, |made| -> deferred_msaa_lab::Result<Presenter> {
            Ok(Presenter {
                view: made.keep(FullscreenPass::new(
                    gl,
                    "viewer present",
                    &present,
                    &outputs,
                )?),
                complex: made.keep(FullscreenPass::new(
                    gl,
                    "viewer complex",
                    &complex,
                    &outputs,
                )?),
                vao: made.keep(VertexArray::new(gl, "viewer vao")?),
            })
        })?;
        Ok(presenter)
    }

    /// Draw `view` of the renderer's last frame into the window's back buffer.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        renderer: &Renderer,
        view: View,
        depth_range: (f32, f32),
        window: PhysicalSize<u32>,
    ) -> AnyResult<()> {
        let gbuffer = renderer.gbuffer();
        let layout = renderer.layout();
        let final_texture = renderer.final_texture().raw();
        // The complex view needs the multisampled key; without MSAA it shows the final image.
        let complex_key = match (view, renderer.retrofit()) {
            (View::Complex, Some(retrofit)) => {
                let (depth, colors, _) = retrofit.inputs()?;
                match retrofit.key() {
                    KeySource::Position(ResolveSlot(k))
                    | KeySource::WorldPosition(ResolveSlot(k)) => {
                        colors.get(k).map(|t| (t.raw(), 2, retrofit.samples()))
                    }
                    KeySource::Depth => Some((depth.raw(), 0, retrofit.samples())),
                }
            }
            _ => None,
        };
        let (texture, mode) = match view {
            View::Final | View::Complex => (final_texture, 0),
            View::Attachment(k) => {
                let mode = match layout.colors[k].name.as_str() {
                    "position" => 2,
                    "normal" => 3,
                    "emissive" => 4,
                    _ => 1,
                };
                (gbuffer.colors[k].raw(), mode)
            }
            View::Depth => (gbuffer.depth.raw(), 5),
        };
        let (near, far) = depth_range;
        let clear = renderer.clear_depth() as f64;
        let depth = DepthProjection::from_matrix(
            &renderer.projection().as_dmat4().to_cols_array(),
            clear == 0.0,
            clear,
        );
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.viewport(0, 0, window.width as i32, window.height as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.color_mask(true, true, true, true);
        }
        let program = if complex_key.is_some() {
            self.complex.program()
        } else {
            self.view.program()
        };
        program.bind(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(texture));
        }
        program.set_i32(gl, "u_image", 0);
        program.set_vec2(gl, "u_window", [window.width as f32, window.height as f32]);
        if let Some((key, component, samples)) = complex_key {
            unsafe {
                gl.active_texture(glow::TEXTURE1);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(key));
            }
            program.set_i32(gl, "u_key", 1);
            program.set_i32(gl, "u_samples", samples as i32);
            program.set_i32(gl, "u_component", component);
        } else {
            program.set_i32(gl, "u_mode", mode);
            program.set_vec4(
                gl,
                "u_depth",
                [
                    depth.p22 as f32,
                    depth.p23 as f32,
                    depth.zero_to_one as i32 as f32,
                    depth.clear_depth as f32,
                ],
            );
            program.set_vec2(gl, "u_range", [near, far]);
        }
        draw_fullscreen_triangle(gl, &self.vao);
        unsafe {
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.use_program(None);
        }
        Ok(check_error(gl, "drawing the view")?)
    }

    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.view.destroy(gl);
        self.complex.destroy(gl);
        self.vao.destroy(gl);
    }
}
