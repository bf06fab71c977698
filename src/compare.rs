//! Image error measures: FLIP (NVIDIA's perceptual metric, through nv-flip),
//! its mean split by a pixel mask, PSNR, and the paper's halo count.

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

#[cfg(test)]
mod tests {
    use super::*;

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
