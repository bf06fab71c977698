//! The depth-aware resolve: its GLSL pass and its CPU reference.

mod settings;

pub use settings::{DepthProjection, ResolveMethod, ResolveRule, ResolveSettings, Window};
