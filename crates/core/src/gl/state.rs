//! The host's GL state that the crate's passes change, captured before and
//! put back after: the crate runs inside the host's context and must leave it
//! as it found it.

use glow::HasContext;
use std::num::NonZeroU32;

/// Texture targets whose binding a pass may change on a unit.
const TEXTURE_TARGETS: [(u32, u32); 3] = [
    (glow::TEXTURE_2D, glow::TEXTURE_BINDING_2D),
    (glow::TEXTURE_2D_ARRAY, glow::TEXTURE_BINDING_2D_ARRAY),
    (
        glow::TEXTURE_2D_MULTISAMPLE,
        glow::TEXTURE_BINDING_2D_MULTISAMPLE,
    ),
];

/// Capabilities a full-screen pass must have off, and that are put back.
const PASS_OFF: [u32; 18] = [
    glow::BLEND,
    glow::CULL_FACE,
    glow::SCISSOR_TEST,
    glow::STENCIL_TEST,
    glow::SAMPLE_MASK,
    glow::SAMPLE_ALPHA_TO_COVERAGE,
    glow::SAMPLE_ALPHA_TO_ONE,
    glow::RASTERIZER_DISCARD,
    glow::COLOR_LOGIC_OP,
    glow::POLYGON_OFFSET_FILL,
    glow::CLIP_DISTANCE0,
    glow::CLIP_DISTANCE1,
    glow::CLIP_DISTANCE2,
    glow::CLIP_DISTANCE3,
    glow::CLIP_DISTANCE4,
    glow::CLIP_DISTANCE5,
    glow::CLIP_DISTANCE6,
    glow::CLIP_DISTANCE7,
];

/// The state a pass changes: bindings, tests, masks and the texture
/// bindings of the units it uses.
pub struct SavedState {
    framebuffer: i32,
    read_framebuffer: i32,
    /// `PASS_OFF`'s capabilities, `GL_DEPTH_TEST` and `GL_FRAMEBUFFER_SRGB`.
    capabilities: Vec<(u32, bool)>,
    scissor_box: [i32; 4],
    polygon_mode: i32,
    program: i32,
    vertex_array: i32,
    active_texture: i32,
    viewport: [i32; 4],
    depth_func: i32,
    depth_mask: bool,
    color_mask: [bool; 4],
    /// Per face (front, back): stencil func, ref, value mask, fail/zfail/zpass
    /// ops, write mask.
    stencil_state: [[i32; 7]; 2],
    /// Per texture unit `0..units`: the 2D, 2D-array and multisample bindings.
    textures: Vec<[i32; 3]>,
}

impl SavedState {
    /// Capture the state, with the texture bindings of units `0..units`.
    pub fn capture(gl: &glow::Context, units: u32) -> Self {
        unsafe {
            let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE);
            let textures = (0..units)
                .map(|k| {
                    gl.active_texture(glow::TEXTURE0 + k);
                    TEXTURE_TARGETS.map(|(_, binding)| gl.get_parameter_i32(binding))
                })
                .collect();
            gl.active_texture(active as u32);
            let mut viewport = [0; 4];
            gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
            let mut scissor_box = [0; 4];
            gl.get_parameter_i32_slice(glow::SCISSOR_BOX, &mut scissor_box);
            let mut polygon_mode = [glow::FILL as i32; 2];
            gl.get_parameter_i32_slice(glow::POLYGON_MODE, &mut polygon_mode);
            let capabilities = PASS_OFF
                .iter()
                .chain(&[glow::DEPTH_TEST, glow::FRAMEBUFFER_SRGB])
                .map(|&cap| (cap, gl.is_enabled(cap)))
                .collect();
            SavedState {
                framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING),
                read_framebuffer: gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING),
                capabilities,
                scissor_box,
                polygon_mode: polygon_mode[0],
                program: gl.get_parameter_i32(glow::CURRENT_PROGRAM),
                vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING),
                active_texture: active,
                textures,
                viewport,
                depth_func: gl.get_parameter_i32(glow::DEPTH_FUNC),
                depth_mask: gl.get_parameter_i32(glow::DEPTH_WRITEMASK) != 0,
                color_mask: {
                    let mut m = [0i32; 4];
                    gl.get_parameter_i32_slice(glow::COLOR_WRITEMASK, &mut m);
                    m.map(|c| c != 0)
                },
                stencil_state: [
                    [
                        glow::STENCIL_FUNC,
                        glow::STENCIL_REF,
                        glow::STENCIL_VALUE_MASK,
                        glow::STENCIL_FAIL,
                        glow::STENCIL_PASS_DEPTH_FAIL,
                        glow::STENCIL_PASS_DEPTH_PASS,
                        glow::STENCIL_WRITEMASK,
                    ]
                    .map(|p| gl.get_parameter_i32(p)),
                    [
                        glow::STENCIL_BACK_FUNC,
                        glow::STENCIL_BACK_REF,
                        glow::STENCIL_BACK_VALUE_MASK,
                        glow::STENCIL_BACK_FAIL,
                        glow::STENCIL_BACK_PASS_DEPTH_FAIL,
                        glow::STENCIL_BACK_PASS_DEPTH_PASS,
                        glow::STENCIL_BACK_WRITEMASK,
                    ]
                    .map(|p| gl.get_parameter_i32(p)),
                ],
            }
        }
    }

    /// Put everything captured back.
    pub fn restore(&self, gl: &glow::Context) {
        fn set(gl: &glow::Context, cap: u32, on: bool) {
            unsafe { if on { gl.enable(cap) } else { gl.disable(cap) } }
        }
        unsafe {
            gl.bind_framebuffer(
                glow::DRAW_FRAMEBUFFER,
                live_framebuffer(gl, self.framebuffer),
            );
            gl.bind_framebuffer(
                glow::READ_FRAMEBUFFER,
                live_framebuffer(gl, self.read_framebuffer),
            );
            let [x, y, w, h] = self.scissor_box;
            gl.scissor(x, y, w, h);
            gl.polygon_mode(glow::FRONT_AND_BACK, self.polygon_mode as u32);
            gl.use_program(
                NonZeroU32::new(self.program as u32)
                    .map(glow::NativeProgram)
                    .filter(|&p| gl.is_program(p)),
            );
            gl.bind_vertex_array(
                NonZeroU32::new(self.vertex_array as u32).map(glow::NativeVertexArray),
            );
            for (k, bindings) in self.textures.iter().enumerate() {
                gl.active_texture(glow::TEXTURE0 + k as u32);
                for ((target, _), raw) in TEXTURE_TARGETS.iter().zip(bindings) {
                    gl.bind_texture(*target, live_texture(gl, *raw));
                }
            }
            gl.active_texture(self.active_texture as u32);
            gl.viewport(
                self.viewport[0],
                self.viewport[1],
                self.viewport[2],
                self.viewport[3],
            );
            gl.depth_func(self.depth_func as u32);
            gl.depth_mask(self.depth_mask);
            let [r, g, b, a] = self.color_mask;
            gl.color_mask(r, g, b, a);
            for (face, state) in [glow::FRONT, glow::BACK]
                .into_iter()
                .zip(self.stencil_state)
            {
                let [func, reference, mask, fail, zfail, zpass, write] = state;
                gl.stencil_func_separate(face, func as u32, reference, mask as u32);
                gl.stencil_op_separate(face, fail as u32, zfail as u32, zpass as u32);
                gl.stencil_mask_separate(face, write as u32);
            }
        }
        for &(cap, on) in &self.capabilities {
            set(gl, cap, on);
        }
    }

    /// Set what a full-screen pass needs whatever the host left on: no
    /// blending, culling, scissor, stencil, sample masking or
    /// alpha-to-coverage, logic op, polygon offset or clip distances,
    /// rasterisation on, filled polygons, every colour channel written.
    /// Depth testing and `GL_FRAMEBUFFER_SRGB` are the pass's own choice.
    pub fn prepare_fullscreen_pass(gl: &glow::Context) {
        unsafe {
            for cap in PASS_OFF {
                gl.disable(cap);
            }
            gl.polygon_mode(glow::FRONT_AND_BACK, glow::FILL);
            gl.color_mask(true, true, true, true);
        }
    }
}

/// Everything set-up calls (creating textures, buffers, framebuffers and
/// programs, probing formats, introspecting the host's framebuffer) may
/// touch, for a retrofit made or rebuilt in the middle of the host's frame:
/// [`SavedState`] over every texture unit, and the renderbuffer, buffer and
/// pixel-store state.
pub struct SetupState {
    passes: SavedState,
    renderbuffer: i32,
    buffers: [(u32, i32); 4],
    pixel_store: [(u32, i32); 4],
    /// The active unit's other texture targets.
    other_textures: [(u32, i32); 3],
}

impl SetupState {
    /// Capture it.
    pub fn capture(gl: &glow::Context) -> Self {
        unsafe {
            let units = gl
                .get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS)
                .clamp(1, 32) as u32;
            let get = |pname: u32| gl.get_parameter_i32(pname);
            SetupState {
                passes: SavedState::capture(gl, units),
                renderbuffer: get(glow::RENDERBUFFER_BINDING),
                buffers: [
                    (glow::ARRAY_BUFFER, get(glow::ARRAY_BUFFER_BINDING)),
                    (
                        glow::PIXEL_PACK_BUFFER,
                        get(glow::PIXEL_PACK_BUFFER_BINDING),
                    ),
                    (
                        glow::PIXEL_UNPACK_BUFFER,
                        get(glow::PIXEL_UNPACK_BUFFER_BINDING),
                    ),
                    (glow::UNIFORM_BUFFER, get(glow::UNIFORM_BUFFER_BINDING)),
                ],
                pixel_store: [
                    glow::PACK_ALIGNMENT,
                    glow::UNPACK_ALIGNMENT,
                    glow::PACK_ROW_LENGTH,
                    glow::UNPACK_ROW_LENGTH,
                ]
                .map(|p| (p, get(p))),
                other_textures: [
                    (
                        glow::TEXTURE_RECTANGLE,
                        get(glow::TEXTURE_BINDING_RECTANGLE),
                    ),
                    (glow::TEXTURE_CUBE_MAP, get(glow::TEXTURE_BINDING_CUBE_MAP)),
                    (glow::TEXTURE_3D, get(glow::TEXTURE_BINDING_3D)),
                ],
            }
        }
    }

    /// Put it back.
    pub fn restore(&self, gl: &glow::Context) {
        self.passes.restore(gl);
        unsafe {
            gl.bind_renderbuffer(
                glow::RENDERBUFFER,
                NonZeroU32::new(self.renderbuffer as u32)
                    .map(glow::NativeRenderbuffer)
                    .filter(|&r| gl.is_renderbuffer(r)),
            );
            for (target, raw) in self.buffers {
                gl.bind_buffer(
                    target,
                    NonZeroU32::new(raw as u32)
                        .map(glow::NativeBuffer)
                        .filter(|&b| gl.is_buffer(b)),
                );
            }
            for (pname, value) in self.pixel_store {
                gl.pixel_store_i32(pname, value);
            }
            for (target, raw) in self.other_textures {
                gl.bind_texture(target, live_texture(gl, raw));
            }
        }
    }
}

/// The framebuffer `raw` names, if it still exists: a binding captured
/// before a call that deleted that object goes back to 0 (binding a deleted
/// name is `GL_INVALID_OPERATION`).
pub(crate) fn live_framebuffer(gl: &glow::Context, raw: i32) -> Option<glow::Framebuffer> {
    NonZeroU32::new(raw as u32)
        .map(glow::NativeFramebuffer)
        .filter(|&f| unsafe { gl.is_framebuffer(f) })
}

/// The texture `raw` names, if it still exists ([`live_framebuffer`]).
pub(crate) fn live_texture(gl: &glow::Context, raw: i32) -> Option<glow::Texture> {
    NonZeroU32::new(raw as u32)
        .map(glow::NativeTexture)
        .filter(|&t| unsafe { gl.is_texture(t) })
}
