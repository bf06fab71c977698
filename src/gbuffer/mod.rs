//! The G-buffer: a declarative layout, its single-sample textures, and the
//! multisampled twins the geometry pass draws into.

mod layout;
mod precision;
mod targets;

pub use layout::{AttachmentDesc, GBufferLayout};
pub use precision::{DepthSetup, HALF_MAX, depth_resolution, precision_warnings};
pub use targets::{GBuffer, MultisampleTwin, TwinSpec};
