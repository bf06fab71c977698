//! Live GL object counters.
//!
//! Counted per thread: a GL context is current on one thread at a time, and
//! tests that run in parallel threads must not see each other's objects.

use std::cell::Cell;

thread_local! {
    static COUNTS: [Cell<i64>; KINDS] = const { [const { Cell::new(0) }; KINDS] };
}

const KINDS: usize = 7;

#[derive(Clone, Copy)]
pub(crate) enum Kind {
    Texture = 0,
    Framebuffer = 1,
    Program = 2,
    Shader = 3,
    Buffer = 4,
    VertexArray = 5,
    Query = 6,
}

pub(crate) fn created(kind: Kind) {
    COUNTS.with(|c| c[kind as usize].set(c[kind as usize].get() + 1));
}

pub(crate) fn destroyed(kind: Kind) {
    COUNTS.with(|c| c[kind as usize].set(c[kind as usize].get() - 1));
}

/// GL objects created through this crate and not yet destroyed, on this thread.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LiveObjects {
    /// Textures of every target.
    pub textures: i64,
    /// Framebuffer objects.
    pub framebuffers: i64,
    /// Linked programs.
    pub programs: i64,
    /// Shader objects (normally zero: they are deleted after linking).
    pub shaders: i64,
    /// Buffer objects.
    pub buffers: i64,
    /// Vertex array objects.
    pub vertex_arrays: i64,
    /// Query objects.
    pub queries: i64,
}

impl LiveObjects {
    /// The sum over all kinds.
    pub fn total(&self) -> i64 {
        self.textures
            + self.framebuffers
            + self.programs
            + self.shaders
            + self.buffers
            + self.vertex_arrays
            + self.queries
    }
}

/// The current counts on this thread.
pub fn live_objects() -> LiveObjects {
    COUNTS.with(|c| LiveObjects {
        textures: c[Kind::Texture as usize].get(),
        framebuffers: c[Kind::Framebuffer as usize].get(),
        programs: c[Kind::Program as usize].get(),
        shaders: c[Kind::Shader as usize].get(),
        buffers: c[Kind::Buffer as usize].get(),
        vertex_arrays: c[Kind::VertexArray as usize].get(),
        queries: c[Kind::Query as usize].get(),
    })
}
