//! The sRGB encoding and the box filter that turns the supersampled
//! reference into an image of the bench's size.

use crate::Error;
use crate::Result;
use crate::compare::srgb_to_linear;
use image::RgbaImage;

/// Linear light to an sRGB-encoded 8-bit value.
pub(super) fn linear_to_srgb(l: f32) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Box-filter `factor`×`factor` blocks of an sRGB-encoded image in linear
/// light (decode, average, encode); the size must divide by `factor`.
pub fn downsample_srgb(img: &RgbaImage, factor: u32) -> Result<RgbaImage> {
    let factor = factor.max(1);
    let (w, h) = img.dimensions();
    if w % factor != 0 || h % factor != 0 {
        return Err(Error::invalid(format!(
            "a {w}x{h} image does not divide into {factor}x{factor} blocks"
        )));
    }
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let n = (factor * factor) as f32;
    Ok(RgbaImage::from_fn(w / factor, h / factor, |x, y| {
        let mut sum = [0f32; 4];
        for dy in 0..factor {
            for dx in 0..factor {
                let p = img.get_pixel(x * factor + dx, y * factor + dy);
                for c in 0..3 {
                    sum[c] += lut[p[c] as usize];
                }
                sum[3] += p[3] as f32;
            }
        }
        image::Rgba([
            linear_to_srgb(sum[0] / n),
            linear_to_srgb(sum[1] / n),
            linear_to_srgb(sum[2] / n),
            (sum[3] / n).round() as u8,
        ])
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downsampling_averages_in_linear_light() {
        let img = RgbaImage::from_fn(4, 4, |x, _| {
            if x % 2 == 0 {
                image::Rgba([255, 255, 255, 255])
            } else {
                image::Rgba([0, 0, 0, 255])
            }
        });
        let small = downsample_srgb(&img, 2).unwrap();
        assert_eq!(small.dimensions(), (2, 2));
        // Half white in linear light is sRGB 188, not 128.
        assert_eq!(small.get_pixel(0, 0)[0], 188);
        assert!(downsample_srgb(&img, 3).is_err());
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
    }
}
