//! The G-buffer: a declarative layout, its single-sample textures, and the
//! multisampled twins the geometry pass draws into.

mod budget;
mod bytes;
mod layout;
mod precision;
mod targets;

pub use budget::{
    DEFAULT_BUDGET_BYTES, DRIVER_FRACTION, DriverMemory, MemoryBudget, SampleChoice, budget_twins,
    choose_samples, gbuffer_bytes, parse_bytes, real_sample_count,
};
pub use bytes::fmt_bytes;
pub use layout::{AttachmentDesc, GBufferLayout};
pub use precision::{DepthSetup, HALF_MAX, depth_resolution, precision_warnings};
pub use targets::{GBuffer, MultisampleTwin, TwinSpec};
