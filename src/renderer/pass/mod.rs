//! The passes every technique's frame shares, each a module beside its
//! shader: the background and its copy into the G-buffer pass's
//! framebuffer, the G-buffer pass, per-pixel and per-sample lighting,
//! transparent objects and the tonemap; with what the full-screen passes
//! share ([`shared`]) and the G-buffer's attachment numbers ([`slots`]).
//!
//! Nothing here names a technique: the techniques (`super::technique`)
//! build on these passes, never the other way round.

pub(crate) mod background;
pub(crate) mod background_copy;
pub(crate) mod geometry;
pub(crate) mod lighting;
pub(crate) mod lighting_per_sample;
pub(crate) mod shared;
pub(crate) mod slots;
pub(crate) mod tonemap;
pub(crate) mod transparent;
