//! What the lab's tests, benches and examples share, written once: the toy
//! host deferred renderer ([`Host`]), a reproducible generator ([`Rng`]),
//! GL projection matrices ([`projection`]), the random triangle scenes
//! the resolve benches measure ([`scene`]) and the random host G-buffers
//! the property test retrofits ([`random_host`]).
//!
//! The zoo's hosts (in the fast tier) are not here: each is written the way
//! its own tutorial or engine writes it, which is the point of them.
#![warn(missing_docs)]

pub mod host;
pub mod projection;
pub mod random_host;
pub mod rng;
pub mod scene;

pub use host::{Host, Output};
pub use rng::Rng;
