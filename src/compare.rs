//! Image error measures: FLIP (NVIDIA's perceptual metric, through nv-flip),
//! its mean split by a pixel mask, PSNR, the paper's halo count, and the
//! motion bench's frame-to-frame measures (the temporal error and the edge
//! sharpness, docs/motion.md).

use image::RgbaImage;

/// FLIP statistics of a test image against a reference.
#[derive(Clone, Debug)]
pub struct FlipStats {
    /// Mean FLIP error, 0 (identical) to 1.
    pub mean: f32,
    /// 95th percentile of the per-pixel error.
    pub p95: f32,
    /// 99th percentile.
    pub p99: f32,
    /// Largest per-pixel error.
    pub max: f32,
    /// The error map, coloured with the magma map, for people to look at.
    pub map: RgbaImage,
}

fn rgb8(img: &RgbaImage) -> nv_flip::FlipImageRgb8 {
    let data: Vec<u8> = img.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
    nv_flip::FlipImageRgb8::with_data(img.width(), img.height(), &data)
}

/// The per-pixel FLIP errors of `test` against `reference` at the default
/// viewing distance, which every FLIP measure here pools; `None` when the
/// sizes differ or are empty.
fn flip_errors(reference: &RgbaImage, test: &RgbaImage) -> Option<nv_flip::FlipImageFloat> {
    if reference.dimensions() != test.dimensions()
        || reference.width() == 0
        || reference.height() == 0
    {
        return None;
    }
    Some(nv_flip::flip(
        rgb8(reference),
        rgb8(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    ))
}

/// FLIP of `test` against `reference` at the default viewing distance.
/// `None` when the sizes differ.
pub fn flip(reference: &RgbaImage, test: &RgbaImage) -> Option<FlipStats> {
    let error = flip_errors(reference, test)?;
    let mut pool = nv_flip::FlipPool::from_image(&error);
    let coloured = error.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let map = RgbaImage::from_fn(reference.width(), reference.height(), |x, y| {
        let i = ((y * reference.width() + x) * 3) as usize;
        image::Rgba([coloured[i], coloured[i + 1], coloured[i + 2], 255])
    });
    Some(FlipStats {
        mean: pool.mean(),
        p95: pool.get_percentile(0.95, false),
        p99: pool.get_percentile(0.99, false),
        max: pool.max_value(),
        map,
    })
}

/// Mean FLIP over the pixels a mask marks and over the rest, see
/// [`flip_by_mask`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipByMask {
    /// Mean FLIP over the marked pixels (`None` when none is marked).
    pub marked: Option<f64>,
    /// Mean FLIP over the unmarked pixels (`None` when all are marked).
    pub unmarked: Option<f64>,
    /// The marked pixels' share of the image, 0 to 1.
    pub marked_share: f64,
}

/// FLIP of `test` against `reference`, its mean split by `mask`: a pixel
/// is marked when its mask value is non-zero (masks are 255 or 0). The
/// per-pixel errors are those [`flip`]'s mean pools, so the two means,
/// weighted by their shares, give that mean. `None` when the three sizes
/// differ.
pub fn flip_by_mask(
    reference: &RgbaImage,
    test: &RgbaImage,
    mask: &image::GrayImage,
) -> Option<FlipByMask> {
    if mask.dimensions() != reference.dimensions() {
        return None;
    }
    let errors = flip_errors(reference, test)?.to_vec();
    let (mut sums, mut counts) = ([0f64; 2], [0usize; 2]);
    for (error, m) in errors.iter().zip(mask.pixels()) {
        let k = usize::from(m[0] != 0);
        sums[k] += f64::from(*error);
        counts[k] += 1;
    }
    let mean = |k: usize| (counts[k] > 0).then(|| sums[k] / counts[k] as f64);
    Some(FlipByMask {
        marked: mean(1),
        unmarked: mean(0),
        marked_share: counts[1] as f64 / (counts[0] + counts[1]).max(1) as f64,
    })
}

/// Peak signal-to-noise ratio over RGB in dB (infinite for identical images).
pub fn psnr(reference: &RgbaImage, test: &RgbaImage) -> f64 {
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (a, b) in reference.pixels().zip(test.pixels()) {
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 || sum == 0.0 {
        return f64::INFINITY;
    }
    let mse = sum / n as f64;
    10.0 * (255.0 * 255.0 / mse).log10()
}

/// Rec. 709 luminance of an 8-bit sRGB-encoded pixel, in 0..1 (display-referred).
pub fn luminance(p: &image::Rgba<u8>) -> f32 {
    (0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32) / 255.0
}

/// Pixels brighter than the reference by more than `threshold` in luminance
/// (the paper's Figure 4 halo artefact; the report uses 0.1).
pub fn halo_pixels(reference: &RgbaImage, test: &RgbaImage, threshold: f32) -> usize {
    reference
        .pixels()
        .zip(test.pixels())
        .filter(|(r, t)| luminance(t) - luminance(r) > threshold)
        .count()
}

/// An 8-bit sRGB value as linear light, 0 to 1.
pub fn srgb_to_linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// CIELAB (D65 white) of an 8-bit sRGB pixel: the space whose differences
/// FLIP's colour pipeline measures (by the HyAB distance), here without
/// FLIP's spatial filtering, so that one pixel's change stays that
/// pixel's.
pub fn lab(p: &image::Rgba<u8>) -> [f32; 3] {
    let (r, g, b) = (
        srgb_to_linear(p[0]),
        srgb_to_linear(p[1]),
        srgb_to_linear(p[2]),
    );
    // Linear sRGB to XYZ, relative to the D65 white.
    let x = (0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b) / 0.950_47;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b;
    let z = (0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b) / 1.088_83;
    let f = |t: f32| {
        const D: f32 = 6.0 / 29.0;
        if t > D * D * D {
            t.cbrt()
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// The temporal error of one pair of consecutive frames: the mean over
/// pixels of the HyAB size of `(I_t − I_{t−1}) − (R_t − R_{t−1})` in
/// CIELAB (`|ΔL| + √(Δa² + Δb²)`), over 100 — change of the test images
/// that the reference does not have (flicker, crawl), or change the
/// reference has that they lack (lag). 0 when the test changes as the
/// reference does; a pixel flickering between black and white where the
/// reference holds still adds 1. `None` when the four sizes differ or are
/// empty.
pub fn temporal_error(
    reference_before: &RgbaImage,
    reference: &RgbaImage,
    test_before: &RgbaImage,
    test: &RgbaImage,
) -> Option<f64> {
    let size = reference.dimensions();
    if [reference_before, test_before, test]
        .iter()
        .any(|i| i.dimensions() != size)
        || size.0 == 0
        || size.1 == 0
    {
        return None;
    }
    let mut sum = 0.0f64;
    for (((r0, r1), t0), t1) in reference_before
        .pixels()
        .zip(reference.pixels())
        .zip(test_before.pixels())
        .zip(test.pixels())
    {
        let (r0, r1, t0, t1) = (lab(r0), lab(r1), lab(t0), lab(t1));
        let d: [f32; 3] = std::array::from_fn(|c| (t1[c] - t0[c]) - (r1[c] - r0[c]));
        sum += f64::from(d[0].abs() + (d[1] * d[1] + d[2] * d[2]).sqrt());
    }
    Some(sum / 100.0 / (f64::from(size.0) * f64::from(size.1)))
}

/// The reference's edges for [`edge_sharpness`]: pixels whose luminance
/// gradient (central differences) is at least this, per pixel.
pub const EDGE_GRADIENT: f32 = 0.05;

/// The luminance gradient magnitude at each pixel (central differences,
/// one-sided at the border).
fn gradients(img: &RgbaImage) -> Vec<f32> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let l: Vec<f32> = img.pixels().map(luminance).collect();
    let mut g = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let at = |x: usize, y: usize| l[y * w + x];
            let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
            let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
            let gx = (at(x1, y) - at(x0, y)) / (x1 - x0).max(1) as f32;
            let gy = (at(x, y1) - at(x, y0)) / (y1 - y0).max(1) as f32;
            g[y * w + x] = (gx * gx + gy * gy).sqrt();
        }
    }
    g
}

/// How sharp `test`'s edges are against the reference's: the mean
/// luminance gradient magnitude of `test` over the reference's edge
/// pixels (gradient at least [`EDGE_GRADIENT`]), over the reference's
/// mean there. 1 is as sharp as the reference; below 1 blurred (a
/// temporal filter's smear), above 1 harsher (aliased steps). `None` when
/// the sizes differ or the reference has no edge.
pub fn edge_sharpness(reference: &RgbaImage, test: &RgbaImage) -> Option<f64> {
    if reference.dimensions() != test.dimensions() || reference.width() == 0 {
        return None;
    }
    let (gr, gt) = (gradients(reference), gradients(test));
    let (mut sr, mut st, mut n) = (0.0f64, 0.0f64, 0usize);
    for (r, t) in gr.iter().zip(&gt) {
        if *r >= EDGE_GRADIENT {
            sr += f64::from(*r);
            st += f64::from(*t);
            n += 1;
        }
    }
    (n > 0 && sr > 0.0).then(|| st / sr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_temporal_error_is_zero_for_the_reference_and_counts_a_flicker() {
        let still = RgbaImage::from_pixel(8, 4, image::Rgba([90, 120, 200, 255]));
        let mut moved = still.clone();
        moved.put_pixel(3, 1, image::Rgba([10, 200, 30, 255]));
        // The reference against itself, moving or not: nothing.
        assert_eq!(temporal_error(&still, &moved, &still, &moved), Some(0.0));
        assert_eq!(temporal_error(&still, &still, &still, &still), Some(0.0));
        // One pixel flickering black to white where the reference holds:
        // ΔL* = 100 over 32 pixels.
        let black = image::Rgba([0, 0, 0, 255]);
        let white = image::Rgba([255, 255, 255, 255]);
        let mut before = still.clone();
        before.put_pixel(0, 0, black);
        let mut after = still.clone();
        after.put_pixel(0, 0, white);
        let e = temporal_error(&still, &still, &before, &after).unwrap();
        assert!((e - 1.0 / 32.0).abs() < 1e-4, "{e}");
        // A method that lags: the reference changes, it does not.
        let lag = temporal_error(&still, &moved, &still, &still).unwrap();
        assert!(lag > 0.0);
        assert_eq!(
            temporal_error(&still, &still, &still, &RgbaImage::new(2, 2)),
            None
        );
    }

    #[test]
    fn lab_matches_known_values() {
        let l = lab(&image::Rgba([255, 255, 255, 255]));
        assert!(
            (l[0] - 100.0).abs() < 0.01 && l[1].abs() < 0.01 && l[2].abs() < 0.01,
            "{l:?}"
        );
        assert_eq!(lab(&image::Rgba([0, 0, 0, 255])), [0.0, 0.0, 0.0]);
        // sRGB red: L* 53.24, a* 80.09, b* 67.20.
        let r = lab(&image::Rgba([255, 0, 0, 255]));
        assert!(
            (r[0] - 53.24).abs() < 0.05 && (r[1] - 80.09).abs() < 0.1 && (r[2] - 67.20).abs() < 0.1,
            "{r:?}"
        );
    }

    #[test]
    fn a_blurred_edge_is_less_sharp_than_the_reference() {
        let edge = RgbaImage::from_fn(16, 8, |x, _| {
            let v = if x < 8 { 0 } else { 255 };
            image::Rgba([v, v, v, 255])
        });
        assert_eq!(edge_sharpness(&edge, &edge), Some(1.0));
        let blurred = RgbaImage::from_fn(16, 8, |x, _| {
            let v = match x {
                0..=6 => 0,
                7 => 85,
                8 => 170,
                _ => 255,
            };
            image::Rgba([v, v, v, 255])
        });
        let s = edge_sharpness(&edge, &blurred).unwrap();
        assert!(s < 1.0, "{s}");
        let flat = RgbaImage::from_pixel(16, 8, image::Rgba([9, 9, 9, 255]));
        assert_eq!(edge_sharpness(&flat, &edge), None);
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = RgbaImage::from_fn(16, 16, |x, y| {
            image::Rgba([(x * 16) as u8, (y * 16) as u8, 77, 255])
        });
        let s = flip(&a, &a).unwrap();
        assert_eq!(s.mean, 0.0);
        assert!(psnr(&a, &a).is_infinite());
        assert_eq!(halo_pixels(&a, &a, 0.1), 0);
    }

    #[test]
    fn differences_are_measured() {
        let a = RgbaImage::from_pixel(16, 16, image::Rgba([40, 40, 40, 255]));
        let mut b = a.clone();
        b.put_pixel(3, 3, image::Rgba([250, 250, 250, 255]));
        let s = flip(&a, &b).unwrap();
        assert!(s.mean > 0.0 && s.max > 0.5, "{s:?}");
        assert!(psnr(&a, &b) < 40.0);
        assert_eq!(halo_pixels(&a, &b, 0.1), 1);
        assert!(flip(&a, &RgbaImage::new(8, 8)).is_none());
    }

    /// The error of a changed corner lands in the mask's marked pixels
    /// when the mask marks that corner, and in the unmarked ones when it
    /// marks the opposite one; either way the shares weight the two means
    /// back to FLIP's mean.
    #[test]
    fn flip_splits_by_the_mask_and_keeps_the_mean() {
        let a = RgbaImage::from_fn(32, 24, |x, y| {
            image::Rgba([(x * 7) as u8, (y * 9) as u8, 90, 255])
        });
        let mut b = a.clone();
        for y in 0..4 {
            for x in 0..4 {
                b.put_pixel(x, y, image::Rgba([255, 255, 255, 255]));
            }
        }
        let corner = |x0: u32, y0: u32| {
            image::GrayImage::from_fn(32, 24, |x, y| {
                let inside = (x0..x0 + 8).contains(&x) && (y0..y0 + 8).contains(&y);
                image::Luma([if inside { 255 } else { 0 }])
            })
        };
        let mean = f64::from(flip(&a, &b).unwrap().mean);
        let near = flip_by_mask(&a, &b, &corner(0, 0)).unwrap();
        let far = flip_by_mask(&a, &b, &corner(24, 16)).unwrap();
        assert_eq!(near.marked_share, 64.0 / (32.0 * 24.0));
        assert_eq!(far.marked_share, near.marked_share);
        let (near_marked, near_unmarked) = (near.marked.unwrap(), near.unmarked.unwrap());
        let (far_marked, far_unmarked) = (far.marked.unwrap(), far.unmarked.unwrap());
        assert!(near_marked > 10.0 * near_unmarked, "{near:?}");
        assert!(far_unmarked > 10.0 * far_marked, "{far:?}");
        for s in [near, far] {
            let weighted =
                s.marked.unwrap() * s.marked_share + s.unmarked.unwrap() * (1.0 - s.marked_share);
            assert!(
                (weighted - mean).abs() < 1e-5 * mean.max(1e-3),
                "{s:?} {mean}"
            );
        }

        let nothing = image::GrayImage::new(32, 24);
        let none_marked = flip_by_mask(&a, &b, &nothing).unwrap();
        assert_eq!(none_marked.marked, None);
        assert_eq!(none_marked.marked_share, 0.0);
        assert!((none_marked.unmarked.unwrap() - mean).abs() < 1e-5 * mean);
        assert!(flip_by_mask(&a, &b, &image::GrayImage::new(8, 8)).is_none());
    }
}
