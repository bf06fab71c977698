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

/// The state a pass changes: bindings, tests, masks and the texture
/// bindings of the units it uses.
pub struct SavedState {
    framebuffer: i32,
    program: i32,
    vertex_array: i32,
    active_texture: i32,
    viewport: [i32; 4],
    depth_test: bool,
    depth_func: i32,
    depth_mask: bool,
    blend: bool,
    cull: bool,
    scissor: bool,
    stencil: bool,
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
            SavedState {
                framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING),
                program: gl.get_parameter_i32(glow::CURRENT_PROGRAM),
                vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING),
                active_texture: active,
                textures,
                viewport,
                depth_test: gl.is_enabled(glow::DEPTH_TEST),
                depth_func: gl.get_parameter_i32(glow::DEPTH_FUNC),
                depth_mask: gl.get_parameter_i32(glow::DEPTH_WRITEMASK) != 0,
                blend: gl.is_enabled(glow::BLEND),
                cull: gl.is_enabled(glow::CULL_FACE),
                scissor: gl.is_enabled(glow::SCISSOR_TEST),
                stencil: gl.is_enabled(glow::STENCIL_TEST),
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
                NonZeroU32::new(self.framebuffer as u32).map(glow::NativeFramebuffer),
            );
            gl.use_program(NonZeroU32::new(self.program as u32).map(glow::NativeProgram));
            gl.bind_vertex_array(
                NonZeroU32::new(self.vertex_array as u32).map(glow::NativeVertexArray),
            );
            for (k, bindings) in self.textures.iter().enumerate() {
                gl.active_texture(glow::TEXTURE0 + k as u32);
                for ((target, _), raw) in TEXTURE_TARGETS.iter().zip(bindings) {
                    gl.bind_texture(
                        *target,
                        NonZeroU32::new(*raw as u32).map(glow::NativeTexture),
                    );
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
        set(gl, glow::DEPTH_TEST, self.depth_test);
        set(gl, glow::BLEND, self.blend);
        set(gl, glow::CULL_FACE, self.cull);
        set(gl, glow::SCISSOR_TEST, self.scissor);
        set(gl, glow::STENCIL_TEST, self.stencil);
    }
}
