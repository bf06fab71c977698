//! The G-buffer: a declarative layout, its single-sample textures, and the
//! multisampled twins the geometry pass draws into.

mod layout;
mod targets;

pub use layout::{AttachmentDesc, GBufferLayout};
pub use targets::{GBuffer, MultisampleTwin, TwinSpec};
