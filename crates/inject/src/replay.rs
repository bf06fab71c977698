//! Two layers by record and replay: after the resolve, the draws the
//! program makes into its lit target up to its next framebuffer bind (its
//! lighting pass, where lighting is the first pass after the G-buffer) are
//! recorded with what they draw with (program, vertex array, the 2D
//! textures of every unit); at that bind they are drawn again into the
//! retrofit's own target between `dmsaa_begin_second_layer_own_target` and
//! `dmsaa_finish_second_layer`, and the state is put back.
//!
//! What is not recorded: uniforms (each program's values as they are at
//! the replay, which is what a pass that sets them before its draws and
//! not between them leaves), clears (the own target comes cleared to the
//! program's clear colour and depth), and texture kinds other than 2D.

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

/// A recorded draw and what it drew with.
#[derive(Clone, Debug)]
pub(crate) struct RecordedDraw {
    pub(crate) call: DrawCall,
    pub(crate) program: u32,
    pub(crate) vertex_array: u32,
    /// (unit, texture) for every unit with a 2D texture bound.
    pub(crate) textures: Vec<(u32, u32)>,
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
    program: u32,
    vertex_array: u32,
    active: u32,
    draw_framebuffer: u32,
    textures: Vec<(u32, u32)>,
}

/// Read what a replay of `draws` will change.
pub(crate) fn save(gl: &glow::Context, draws: &[RecordedDraw]) -> Saved {
    let mut units: Vec<u32> = draws
        .iter()
        .flat_map(|d| d.textures.iter().map(|&(u, _)| u))
        .collect();
    units.sort_unstable();
    units.dedup();
    // SAFETY: queries of the current context; the unit switch is put back.
    unsafe {
        let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
        let textures = units
            .iter()
            .map(|&u| {
                gl.active_texture(glow::TEXTURE0 + u);
                (u, gl.get_parameter_i32(glow::TEXTURE_BINDING_2D) as u32)
            })
            .collect();
        gl.active_texture(active);
        Saved {
            program: gl.get_parameter_i32(glow::CURRENT_PROGRAM) as u32,
            vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING) as u32,
            active,
            draw_framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) as u32,
            textures,
        }
    }
}

/// Draw `draws` again into the bound draw framebuffer.
pub(crate) fn draw(gl: &glow::Context, draws: &[RecordedDraw]) {
    // SAFETY: the program's own objects and calls, as it made them.
    unsafe {
        for d in draws {
            gl.use_program(program(d.program));
            gl.bind_vertex_array(vertex_array(d.vertex_array));
            for &(unit, name) in &d.textures {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, texture(name));
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

/// Put back what [`save`] read.
pub(crate) fn restore(gl: &glow::Context, saved: &Saved) {
    // SAFETY: the names the context had bound, bound again.
    unsafe {
        for &(unit, name) in &saved.textures {
            gl.active_texture(glow::TEXTURE0 + unit);
            gl.bind_texture(glow::TEXTURE_2D, texture(name));
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
