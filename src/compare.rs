//! Image error measures: FLIP (NVIDIA's perceptual metric, through nv-flip),
//! PSNR, and the paper's halo count.

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

/// FLIP of `test` against `reference` at the default viewing distance.
/// `None` when the sizes differ.
pub fn flip(reference: &RgbaImage, test: &RgbaImage) -> Option<FlipStats> {
    if reference.dimensions() != test.dimensions()
        || reference.width() == 0
        || reference.height() == 0
    {
        return None;
    }
    let error = nv_flip::flip(
        rgb8(reference),
        rgb8(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
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
}
