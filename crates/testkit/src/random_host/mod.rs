//! Random host G-buffers: the layouts engines we have not seen could build,
//! drawn from a seed ([`HostSpec::generate`]) and built with raw GL calls
//! the way a host writes them ([`RandomHost::build`]).
//!
//! A [`HostSpec`] is plain data: the colour attachments (point, internal
//! format as the host asks for it, sized or unsized, and the image kind:
//! a 2D texture, a renderbuffer, a layer of an array texture, and rarely
//! what the retrofit must refuse), the draw-buffer list with `GL_NONE`
//! gaps, the depth (every depth and depth-stencil format, as a texture,
//! a renderbuffer or a layer, or missing), the size, and the retrofit
//! options the host's integrator would pass (position and normal
//! attachments, rules, layers, stencil copy, budget). The property test
//! shrinks it by editing it and building again, so everything a case is
//! made of is written out in it.

mod build;
mod formats;
mod spec;

pub use build::{HostIncomplete, RandomHost, ValueKind};
pub use formats::{COLOR_FORMATS, DEPTH_FORMATS, HostFormat, STENCIL_ONLY};
pub use spec::{ColorSpec, DepthPoint, DepthSpec, HostSpec, Limits, Storage, random_options};

#[cfg(test)]
mod tests {

    use super::spec::*;

    #[test]
    fn a_seed_is_one_host() {
        let limits = Limits {
            color_attachments: 8,
            draw_buffers: 8,
        };
        for seed in 0..200 {
            let a = HostSpec::generate(seed, limits);
            assert_eq!(a, HostSpec::generate(seed, limits));
            let points: Vec<u32> = a.colors.iter().map(|c| c.point).collect();
            let mut sorted = points.clone();
            sorted.dedup();
            assert_eq!(points, sorted, "distinct points in order");
            assert!(a.draw_buffers.len() as u32 <= limits.draw_buffers);
            for b in a.draw_buffers.iter().flatten() {
                assert!(
                    points.contains(b),
                    "seed {seed}: draws only what is attached"
                );
            }
        }
        assert_ne!(HostSpec::generate(1, limits), HostSpec::generate(2, limits));
    }
}
