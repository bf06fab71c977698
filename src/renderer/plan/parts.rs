//! The pieces a [`Plan`](super::Plan) is made of: its attachments, what it
//! left out or kept and why, and the programs it compiles.

use crate::gl::Format;

/// One attachment of the planned G-buffer.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PlannedAttachment {
    /// `color`, `position`, …, `depth`.
    pub name: String,
    /// Its internal format.
    pub format: Format,
    /// Whether the method needs it multisampled (a twin with the plan's
    /// sample count beside the single-sample texture).
    pub multisampled: bool,
}

/// Something the scene does not need, and why.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct LeftOut {
    /// An attachment, a pass, or a format (`position RGBA32F`).
    pub name: String,
    /// Why this scene does without it.
    pub why: String,
}

/// One shader program the frame compiles, with its `#define`s.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Permutation {
    /// The program.
    pub program: String,
    /// Its defines, `NAME` or `NAME=VALUE`.
    pub defines: Vec<String>,
}
