//! The options of method `taa` and its jitter sequence.

use crate::{Error, Result};

/// The options of [`AaMode::Taa`](crate::renderer::AaMode::Taa), as `taa:alpha=F:phases=N` spells them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaaOptions {
    /// The weight of the new frame in the exponential blend, in (0, 1]
    /// (`taa:alpha=F`). Default 0.1.
    pub alpha: f32,
    /// How many jitter offsets the Halton (2, 3) sequence cycles through,
    /// 2 to [`MAX_TAA_PHASES`] (`taa:phases=N`). Default 8.
    pub phases: u32,
}

/// The most jitter phases [`TaaOptions::phases`] takes.
pub const MAX_TAA_PHASES: u32 = 256;

impl Default for TaaOptions {
    /// Blend factor 0.1, 8 phases.
    fn default() -> Self {
        TaaOptions {
            alpha: 0.1,
            phases: 8,
        }
    }
}

impl TaaOptions {
    /// Check the blend factor and the phase count (one-line errors).
    pub fn validate(&self) -> Result<()> {
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return Err(Error::invalid(format!(
                "taa's alpha={} is not a blend factor in (0, 1]",
                self.alpha
            )));
        }
        if !(2..=MAX_TAA_PHASES).contains(&self.phases) {
            return Err(Error::invalid(format!(
                "taa's phases={} is not a jitter phase count in 2..={MAX_TAA_PHASES}",
                self.phases
            )));
        }
        Ok(())
    }

    /// How many frames the history needs, from a reset, before what is
    /// left of the first frame weighs under 1% (`(1 − alpha)^n < 0.01`),
    /// and at least one full cycle of the jitter: the frames a still frame
    /// is rendered after, when it is measured.
    pub fn warmup_frames(&self) -> u32 {
        let alpha = f64::from(self.alpha.clamp(1e-3, 1.0));
        let settle = if alpha >= 1.0 {
            0.0
        } else {
            (0.01f64.ln() / (1.0 - alpha).ln()).ceil()
        };
        (settle as u32).max(self.phases)
    }

    /// The sub-pixel offset of frame `index` (0, 1, … from a reset), in
    /// pixels within (−0.5, 0.5): Halton (2, 3) points 1 to `phases` in
    /// turn, centred on the pixel (point 0 is the corner, so it is left out).
    pub fn jitter(&self, index: u64) -> [f32; 2] {
        let k = index % u64::from(self.phases.max(1)) + 1;
        [
            (radical_inverse(k, 2) - 0.5) as f32,
            (radical_inverse(k, 3) - 0.5) as f32,
        ]
    }
}

/// `k`'s digits in `base` mirrored about the radix point: the `k`-th point
/// of the van der Corput sequence in that base, in [0, 1).
fn radical_inverse(mut k: u64, base: u64) -> f64 {
    let (mut value, mut scale) = (0.0, 1.0 / base as f64);
    while k > 0 {
        value += (k % base) as f64 * scale;
        k /= base;
        scale /= base as f64;
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jitter_is_halton_2_3_centred_and_cycles() {
        let o = TaaOptions::default();
        // Halton (2, 3) points 1, 2, 3: (1/2, 1/3), (1/4, 2/3), (3/4, 1/9).
        let want = [
            [0.0, -1.0 / 6.0],
            [-0.25, 1.0 / 6.0],
            [0.25, 1.0 / 9.0 - 0.5],
        ];
        for (k, w) in want.iter().enumerate() {
            let j = o.jitter(k as u64);
            assert!(
                (j[0] - w[0]).abs() < 1e-6 && (j[1] - w[1]).abs() < 1e-6,
                "{k}: {j:?}"
            );
        }
        assert_eq!(o.jitter(8), o.jitter(0));
        let mut seen: Vec<[f32; 2]> = (0..8).map(|k| o.jitter(k)).collect();
        seen.dedup();
        assert_eq!(seen.len(), 8);
        assert!(seen.iter().flatten().all(|v| v.abs() < 0.5));
    }

    #[test]
    fn warmup_covers_the_blend_and_a_cycle() {
        assert_eq!(TaaOptions::default().warmup_frames(), 44);
        let fast = TaaOptions {
            alpha: 0.5,
            phases: 16,
        };
        assert_eq!(fast.warmup_frames(), 16);
    }
}
