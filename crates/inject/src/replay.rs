//! Two layers by record and replay: after the resolve, the draws the
//! program makes into its lit target up to its next framebuffer bind (its
//! lighting pass, where lighting is the first pass after the G-buffer) are
//! recorded with what they draw with (program, vertex array, the 2D
//! textures of every unit); at that bind they are drawn again into the
//! retrofit's own target between `dmsaa_begin_second_layer_own_target` and
//! `dmsaa_finish_second_layer`, and the state is put back.
//!
//! Recorded with each draw: the uniform calls the program made since the
//! last one (a light volume's position and colour, set before its draw),
//! and the blend and depth state it drew with (additive lights with depth
//! writes off, an ambient pass before them with neither); the pass's
//! colour clear is made again on the own target (its depth and stencil
//! are the library's). What is not recorded: uniform blocks and buffers
//! written between draws, other state, and texture kinds other than 2D.

use glow::HasContext;
use std::num::NonZeroU32;

/// One draw call, with its arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DrawCall {
    /// `glDrawArrays`.
    Arrays { mode: u32, first: i32, count: i32 },
    /// `glDrawArraysInstanced`.
    ArraysInstanced {
        mode: u32,
        first: i32,
        count: i32,
        instances: i32,
    },
    /// `glDrawElements` and `glDrawRangeElements` (the range is a hint).
    Elements {
        mode: u32,
        count: i32,
        kind: u32,
        offset: usize,
    },
    /// `glDrawElementsInstanced`.
    ElementsInstanced {
        mode: u32,
        count: i32,
        kind: u32,
        offset: usize,
        instances: i32,
    },
    /// `glDrawElementsBaseVertex`.
    ElementsBaseVertex {
        mode: u32,
        count: i32,
        kind: u32,
        offset: usize,
        base: i32,
    },
}

/// A `glUniform*` call as the program made it, on the program then bound.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct UniformCall {
    pub(crate) program: u32,
    pub(crate) location: i32,
    pub(crate) value: UniformValue,
}

/// A uniform call's values, by its kind.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum UniformValue {
    /// `glUniform{1,2,3,4}f[v]`: the components per element, the values.
    Float(u8, Vec<f32>),
    /// `glUniform{1,2,3,4}i[v]`.
    Int(u8, Vec<i32>),
    /// `glUniformMatrix4fv`, untransposed.
    Matrix4(Vec<f32>),
}

/// A uniform buffer's binding or contents changed between two draws of
/// the recording (a light's values written into the block it reads).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum BufferChange {
    /// `glBindBufferBase` (`size` 0) or `glBindBufferRange` on
    /// `GL_UNIFORM_BUFFER`.
    Bind {
        index: u32,
        buffer: u32,
        offset: i32,
        size: i32,
    },
    /// `glBufferSubData` into the buffer bound at `GL_UNIFORM_BUFFER`.
    Data {
        buffer: u32,
        offset: i32,
        bytes: Vec<u8>,
    },
}

/// The blend and depth state a draw was made with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct DrawState {
    blend: bool,
    /// src rgb, dst rgb, src alpha, dst alpha.
    blend_func: [u32; 4],
    /// rgb, alpha.
    blend_equation: [u32; 2],
    depth_test: bool,
    depth_func: u32,
    depth_mask: bool,
}

impl DrawState {
    /// The state as GL has it now.
    pub(crate) fn read(gl: &glow::Context) -> Self {
        // SAFETY: queries of the current context.
        unsafe {
            let get = |p: u32| gl.get_parameter_i32(p) as u32;
            DrawState {
                blend: gl.is_enabled(glow::BLEND),
                blend_func: [
                    get(glow::BLEND_SRC_RGB),
                    get(glow::BLEND_DST_RGB),
                    get(glow::BLEND_SRC_ALPHA),
                    get(glow::BLEND_DST_ALPHA),
                ],
                blend_equation: [
                    get(glow::BLEND_EQUATION_RGB),
                    get(glow::BLEND_EQUATION_ALPHA),
                ],
                depth_test: gl.is_enabled(glow::DEPTH_TEST),
                depth_func: get(glow::DEPTH_FUNC),
                depth_mask: gl.get_parameter_i32(glow::DEPTH_WRITEMASK) != 0,
            }
        }
    }

    /// Make it GL's.
    fn apply(&self, gl: &glow::Context) {
        // SAFETY: state calls of the current context.
        unsafe {
            let set = |cap: u32, on: bool| {
                if on { gl.enable(cap) } else { gl.disable(cap) }
            };
            set(glow::BLEND, self.blend);
            let [sr, dr, sa, da] = self.blend_func;
            gl.blend_func_separate(sr, dr, sa, da);
            gl.blend_equation_separate(self.blend_equation[0], self.blend_equation[1]);
            set(glow::DEPTH_TEST, self.depth_test);
            gl.depth_func(self.depth_func);
            gl.depth_mask(self.depth_mask);
        }
    }
}

/// A recorded draw and what it drew with.
#[derive(Clone, Debug)]
pub(crate) struct RecordedDraw {
    pub(crate) call: DrawCall,
    pub(crate) program: u32,
    pub(crate) vertex_array: u32,
    /// (unit, target, texture) for every unit with a 2D or 2D-array texture
    /// bound (a G-buffer of one array's layers is read through the array).
    pub(crate) textures: Vec<(u32, u32, u32)>,
    /// The uniform calls made since the recording's last draw.
    pub(crate) uniforms: Vec<UniformCall>,
    /// The uniform buffers' changes since the recording's last draw.
    pub(crate) buffers: Vec<BufferChange>,
    /// The framebuffer it drew into (the program's name).
    pub(crate) framebuffer: u32,
    /// The blend and depth state it drew with.
    pub(crate) state: DrawState,
}

/// The draws after one resolve.
#[derive(Clone, Debug, Default)]
pub(crate) struct Recording {
    /// The framebuffer drawn into (the program's name; 0: the default), set
    /// by the first draw.
    pub(crate) target: Option<u32>,
    pub(crate) draws: Vec<RecordedDraw>,
    /// Passes still to let go by before the lighting (the profile's
    /// `lighting.pass` - 1).
    pub(crate) skip: u32,
    /// Uniform calls made since the last recorded draw (the next one's).
    pub(crate) uniforms: Vec<UniformCall>,
    /// Uniform-buffer changes since the last recorded draw (the next one's).
    pub(crate) buffers: Vec<BufferChange>,
    /// The colour clears made before a pass's first draw: (the draw they
    /// come before, the framebuffer, the colour).
    pub(crate) clears: Vec<(usize, u32, [f32; 4])>,
    /// Passes of the lighting still to come after the one being recorded.
    pub(crate) passes_left: u32,
    /// Whether the lighting spans several passes (draws into any
    /// framebuffer are its), not one (draws into the first one's only).
    pub(crate) multi_pass: bool,
    /// Whether the pass being recorded drew.
    pub(crate) pass_drawn: bool,
}

impl Recording {
    /// A pass let go by (one before the lighting).
    pub(crate) fn let_go(&mut self) {
        self.draws.clear();
        self.target = None;
        self.uniforms.clear();
        self.buffers.clear();
        self.clears.clear();
        self.pass_drawn = false;
    }
}

fn program(name: u32) -> Option<glow::Program> {
    NonZeroU32::new(name).map(glow::NativeProgram)
}

fn vertex_array(name: u32) -> Option<glow::VertexArray> {
    NonZeroU32::new(name).map(glow::NativeVertexArray)
}

fn texture(name: u32) -> Option<glow::Texture> {
    NonZeroU32::new(name).map(glow::NativeTexture)
}

/// The state a replay changes, read before it.
pub(crate) struct Saved {
    state: DrawState,
    /// (index, buffer, start, size) of every uniform-buffer binding point
    /// the replay binds.
    bindings: Vec<(u32, u32, i32, i32)>,
    uniform_buffer: u32,
    copy_write_buffer: u32,
    program: u32,
    vertex_array: u32,
    active: u32,
    draw_framebuffer: u32,
    /// (unit, target, texture) bound before, for every unit and target the
    /// replay binds.
    textures: Vec<(u32, u32, u32)>,
}

/// Read what a replay of `draws` will change.
pub(crate) fn save(gl: &glow::Context, draws: &[RecordedDraw]) -> Saved {
    let mut units: Vec<(u32, u32)> = draws
        .iter()
        .flat_map(|d| d.textures.iter().map(|&(u, target, _)| (u, target)))
        .collect();
    units.sort_unstable();
    units.dedup();
    // SAFETY: queries of the current context; the unit switch is put back.
    unsafe {
        let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
        let textures = units
            .iter()
            .map(|&(u, target)| {
                gl.active_texture(glow::TEXTURE0 + u);
                let binding = if target == glow::TEXTURE_2D_ARRAY {
                    glow::TEXTURE_BINDING_2D_ARRAY
                } else {
                    glow::TEXTURE_BINDING_2D
                };
                (u, target, gl.get_parameter_i32(binding) as u32)
            })
            .collect();
        gl.active_texture(active);
        let mut indices: Vec<u32> = draws
            .iter()
            .flat_map(|d| d.buffers.iter())
            .filter_map(|b| match b {
                BufferChange::Bind { index, .. } => Some(*index),
                BufferChange::Data { .. } => None,
            })
            .collect();
        indices.sort_unstable();
        indices.dedup();
        let bindings = indices
            .iter()
            .map(|&i| {
                (
                    i,
                    gl.get_parameter_indexed_i32(glow::UNIFORM_BUFFER_BINDING, i) as u32,
                    gl.get_parameter_indexed_i32(glow::UNIFORM_BUFFER_START, i),
                    gl.get_parameter_indexed_i32(glow::UNIFORM_BUFFER_SIZE, i),
                )
            })
            .collect();
        Saved {
            state: DrawState::read(gl),
            bindings,
            uniform_buffer: gl.get_parameter_i32(glow::UNIFORM_BUFFER_BINDING) as u32,
            copy_write_buffer: gl.get_parameter_i32(glow::COPY_WRITE_BUFFER_BINDING) as u32,
            program: gl.get_parameter_i32(glow::CURRENT_PROGRAM) as u32,
            vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING) as u32,
            active,
            draw_framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) as u32,
            textures,
        }
    }
}

/// Draw `draws` again, each into its framebuffer, the lit target's
/// (`output`) replaced by `own`, with `clears` made again before the draws
/// they came before (the own target's colour attachment 0; another
/// framebuffer's draw buffers with `glClear` and the clear colour it had).
pub(crate) fn draw(
    gl: &glow::Context,
    draws: &[RecordedDraw],
    clears: &[(usize, u32, [f32; 4])],
    output: u32,
    own: u32,
) {
    let fbo = |n: u32| NonZeroU32::new(n).map(glow::NativeFramebuffer);
    let into = |n: u32| if n == output { own } else { n };
    // SAFETY: the program's own objects and calls, as it made them; the
    // clear colour put back after each clear of the program's framebuffers.
    unsafe {
        let mut bound = own;
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, fbo(own));
        for (k, d) in draws.iter().enumerate() {
            for &(_, framebuffer, colour) in clears.iter().filter(|c| c.0 == k) {
                let target = into(framebuffer);
                if target != bound {
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, fbo(target));
                    bound = target;
                }
                if target == own {
                    gl.clear_buffer_f32_slice(glow::COLOR, 0, &colour);
                } else {
                    let mut was = [0f32; 4];
                    gl.get_parameter_f32_slice(glow::COLOR_CLEAR_VALUE, &mut was);
                    gl.clear_color(colour[0], colour[1], colour[2], colour[3]);
                    gl.clear(glow::COLOR_BUFFER_BIT);
                    gl.clear_color(was[0], was[1], was[2], was[3]);
                }
            }
            let target = into(d.framebuffer);
            if target != bound {
                gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, fbo(target));
                bound = target;
            }
            for b in &d.buffers {
                change_buffer(gl, b);
            }
            for u in &d.uniforms {
                gl.use_program(program(u.program));
                set_uniform(gl, u);
            }
            d.state.apply(gl);
            gl.use_program(program(d.program));
            gl.bind_vertex_array(vertex_array(d.vertex_array));
            for &(unit, target, name) in &d.textures {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(target, texture(name));
            }
            match d.call {
                DrawCall::Arrays { mode, first, count } => gl.draw_arrays(mode, first, count),
                DrawCall::ArraysInstanced {
                    mode,
                    first,
                    count,
                    instances,
                } => gl.draw_arrays_instanced(mode, first, count, instances),
                DrawCall::Elements {
                    mode,
                    count,
                    kind,
                    offset,
                } => gl.draw_elements(mode, count, kind, offset as i32),
                DrawCall::ElementsInstanced {
                    mode,
                    count,
                    kind,
                    offset,
                    instances,
                } => gl.draw_elements_instanced(mode, count, kind, offset as i32, instances),
                DrawCall::ElementsBaseVertex {
                    mode,
                    count,
                    kind,
                    offset,
                    base,
                } => gl.draw_elements_base_vertex(mode, count, kind, offset as i32, base),
            }
        }
    }
}

/// Make one recorded uniform call again on the bound program.
///
/// # Safety
///
/// The call's program is bound; its location is that program's.
unsafe fn set_uniform(gl: &glow::Context, u: &UniformCall) {
    let location = glow::NativeUniformLocation(u.location as u32);
    let l = Some(&location);
    // SAFETY: the caller's.
    unsafe {
        match &u.value {
            UniformValue::Float(1, v) => gl.uniform_1_f32_slice(l, v),
            UniformValue::Float(2, v) => gl.uniform_2_f32_slice(l, v),
            UniformValue::Float(3, v) => gl.uniform_3_f32_slice(l, v),
            UniformValue::Float(_, v) => gl.uniform_4_f32_slice(l, v),
            UniformValue::Int(1, v) => gl.uniform_1_i32_slice(l, v),
            UniformValue::Int(2, v) => gl.uniform_2_i32_slice(l, v),
            UniformValue::Int(3, v) => gl.uniform_3_i32_slice(l, v),
            UniformValue::Int(_, v) => gl.uniform_4_i32_slice(l, v),
            UniformValue::Matrix4(v) => gl.uniform_matrix_4_f32_slice(l, false, v),
        }
    }
}

fn buffer(name: u32) -> Option<glow::Buffer> {
    NonZeroU32::new(name).map(glow::NativeBuffer)
}

/// Make one recorded uniform-buffer change again.
///
/// # Safety
///
/// The program's buffers, as it used them.
unsafe fn change_buffer(gl: &glow::Context, change: &BufferChange) {
    // SAFETY: the caller's.
    unsafe {
        match change {
            BufferChange::Bind {
                index,
                buffer: b,
                offset,
                size,
            } => {
                if *size > 0 {
                    gl.bind_buffer_range(glow::UNIFORM_BUFFER, *index, buffer(*b), *offset, *size)
                } else {
                    gl.bind_buffer_base(glow::UNIFORM_BUFFER, *index, buffer(*b))
                }
            }
            BufferChange::Data {
                buffer: b,
                offset,
                bytes,
            } => {
                gl.bind_buffer(glow::COPY_WRITE_BUFFER, buffer(*b));
                gl.buffer_sub_data_u8_slice(glow::COPY_WRITE_BUFFER, *offset, bytes);
            }
        }
    }
}

/// Put back what [`save`] read.
pub(crate) fn restore(gl: &glow::Context, saved: &Saved) {
    saved.state.apply(gl);
    // SAFETY: the names the context had bound, bound again.
    unsafe {
        for &(index, b, start, size) in &saved.bindings {
            if size > 0 {
                gl.bind_buffer_range(glow::UNIFORM_BUFFER, index, buffer(b), start, size);
            } else {
                gl.bind_buffer_base(glow::UNIFORM_BUFFER, index, buffer(b));
            }
        }
        gl.bind_buffer(glow::UNIFORM_BUFFER, buffer(saved.uniform_buffer));
        gl.bind_buffer(glow::COPY_WRITE_BUFFER, buffer(saved.copy_write_buffer));
        for &(unit, target, name) in &saved.textures {
            gl.active_texture(glow::TEXTURE0 + unit);
            gl.bind_texture(target, texture(name));
        }
        gl.active_texture(saved.active);
        gl.bind_vertex_array(vertex_array(saved.vertex_array));
        gl.use_program(program(saved.program));
        gl.bind_framebuffer(
            glow::DRAW_FRAMEBUFFER,
            NonZeroU32::new(saved.draw_framebuffer).map(glow::NativeFramebuffer),
        );
    }
}
