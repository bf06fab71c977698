//! Halo pixels, told apart from coverage quantisation.
//!
//! A multisampled pixel knows its surfaces' coverage in steps of one
//! sample, `k` of `n`; the 16x image in steps of one sixteenth. Where a
//! bright surface covers 5 of the 16x image's 16 positions, a 4x pixel may
//! see it at 2 of its 4 samples, and mixing `2/4` of it in linear light
//! (as the 16x image averages) is brighter than the 16x pixel by more than
//! the halo threshold on a dark-against-sky silhouette. That pixel is no
//! halo: no mix of the pixel's own surfaces at the sample coverage is
//! closer. A halo is light the pixel's surfaces at their coverage cannot
//! give: a surface taken whole where the samples saw it in part, or a
//! colour lit from an averaged position or normal (a blit-resolved
//! G-buffer lights the air between an edge's two surfaces).
//!
//! So a pixel's bound is the brightest image its surfaces give with one
//! sample's share of its area (`1/n`) moved from its darkest to its
//! brightest surface: the 16x image's positions of the pixel in linear
//! light, the darkest `16/n` replaced by the brightest, averaged, encoded.
//! A pixel is a halo where its luminance (display-referred, as
//! `compare::luminance`) is over that bound's by more than the threshold.

use deferred_msaa_lab::compare::{luminance, srgb_to_linear};
use image::RgbaImage;

/// Each pixel's brightest luminance its surfaces explain at `samples`
/// samples: `big` is the host's render at `ss` times each way.
pub fn bounds(big: &RgbaImage, ss: u32, samples: u32) -> Vec<f32> {
    let (w, h) = (big.width() / ss, big.height() / ss);
    let positions = (ss * ss) as usize;
    // One sample's share of the pixel, in the 16x image's positions.
    let moved = positions.div_ceil(samples.max(1) as usize);
    let mut out = Vec::with_capacity((w * h) as usize);
    let mut block: Vec<[f32; 3]> = Vec::with_capacity(positions);
    for y in 0..h {
        for x in 0..w {
            block.clear();
            for dy in 0..ss {
                for dx in 0..ss {
                    let p = big.get_pixel(x * ss + dx, y * ss + dy);
                    block.push([0, 1, 2].map(|c| srgb_to_linear(p[c])));
                }
            }
            let light = |c: &[f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
            block.sort_by(|a, b| light(a).total_cmp(&light(b)));
            let brightest = block[positions - 1];
            let mut sum = [0f32; 3];
            for (i, c) in block.iter().enumerate() {
                let c = if i < moved { &brightest } else { c };
                for k in 0..3 {
                    sum[k] += c[k];
                }
            }
            let encoded = sum.map(|s| encode(s / positions as f32));
            out.push(luminance(&image::Rgba([
                encoded[0], encoded[1], encoded[2], 255,
            ])));
        }
    }
    out
}

/// Whether `test`'s pixel at `(x, y)` is a halo against `bounds`.
pub fn is_halo(bounds: &[f32], test: &RgbaImage, x: u32, y: u32, threshold: f32) -> bool {
    luminance(test.get_pixel(x, y)) - bounds[(y * test.width() + x) as usize] > threshold
}

/// The halo pixels of `test`, and of them those where `other` has none.
pub fn count(
    bounds: &[f32],
    test: &RgbaImage,
    other: &RgbaImage,
    threshold: f32,
) -> (usize, usize) {
    let (mut all, mut new) = (0, 0);
    for y in 0..test.height() {
        for x in 0..test.width() {
            if is_halo(bounds, test, x, y, threshold) {
                all += 1;
                if !is_halo(bounds, other, x, y, threshold) {
                    new += 1;
                }
            }
        }
    }
    (all, new)
}

/// Linear light to an 8-bit sRGB value, rounded.
fn encode(l: f32) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round() as u8
}
