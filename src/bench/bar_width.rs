//! The bar width error: how much wider or thinner than the reference a
//! method draws a scene's thin bars ([`Scene::bars`](crate::scene::Scene::bars)),
//! in pixels.
//!
//! Each bar is measured along scanlines: image rows for a bar nearer
//! vertical than horizontal, columns otherwise. A scanline's *band* is the
//! stretch of it the bar crosses plus [`BAND_MARGIN_PX`] on either side,
//! and the bar covers a fraction of each band pixel, read from the pixel's
//! luminance in linear light:
//!
//! `coverage = clamp((L - L_behind) / (L_bar - L_behind), 0, 1)`
//!
//! The scanline's width is the band's coverage summed times the cosine of
//! the angle between the bar and the scanlines' normal (what turns a width
//! along the scanline into one across the bar). Both luminances come from
//! the reference: `L_behind` is the median over the band pixels that are
//! clear of the bar, and `L_bar` is the value that makes the reference's
//! coverage, summed over all the bar's scanlines, equal to the bar's own
//! width (a bar a pixel or two wide may cover no pixel whole, so no pixel
//! shows `L_bar` alone). A method's error on a bar is the mean over its
//! scanlines of the method's width less the reference's, and the bar width
//! error is the mean of that over the bars, each bar counting alike:
//! negative when a method draws the bars thinner than the reference.

pub use super::bar_width_error::BarWidthError;

use crate::compare::srgb_to_linear;
use crate::scene::{Bar, Camera, ImageBar};
use glam::DVec2;
use image::RgbaImage;

/// Pixels on either side of a bar, along each scanline, that its band
/// takes in beyond the bar itself: room for what a method smears past the
/// bar's edges, and for pixels clear of it.
pub const BAND_MARGIN_PX: f64 = 3.0;

/// The smallest difference in linear luminance between a bar and what is
/// behind it that its width is measured from.
pub const MIN_CONTRAST: f64 = 0.05;

/// `bars` as a `width`×`height` image rendered from `camera` shows them.
pub fn image_bars(
    bars: &[Bar],
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<Vec<ImageBar>, BarWidthError> {
    bars.iter()
        .enumerate()
        .map(|(bar, b)| {
            b.in_image(camera, width, height)
                .ok_or(BarWidthError::NotInView { bar })
        })
        .collect()
}

/// A pixel of a band.
#[derive(Debug, Clone, Copy)]
struct BandPixel {
    x: u32,
    y: u32,
    /// Whether the bar cannot reach into the pixel, so it shows only what
    /// is behind.
    clear: bool,
}

/// One bar's scanlines and the luminances its coverage is read between.
#[derive(Debug, Clone)]
struct GaugedBar {
    bands: Vec<Vec<BandPixel>>,
    /// The cosine turning a width along a scanline into one across the bar.
    cos: f64,
    behind: f64,
    bar: f64,
    /// The reference's width, the mean over the bands.
    reference_width: f64,
}

/// The bars of one scene as its reference shows them, ready to measure
/// the images of the methods against.
#[derive(Debug, Clone)]
pub struct BarGauge {
    width: u32,
    height: u32,
    bars: Vec<GaugedBar>,
}

/// Linear-light Rec. 709 luminance of an sRGB-encoded pixel.
fn linear_luminance(p: &image::Rgba<u8>) -> f64 {
    f64::from(
        0.2126 * srgb_to_linear(p[0])
            + 0.7152 * srgb_to_linear(p[1])
            + 0.0722 * srgb_to_linear(p[2]),
    )
}

/// The median of `values` (0 for none).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => 0.0,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// The bands of `bar` that lie wholly inside a `width`×`height` image, and
/// the cosine of the bar's angle to the scanlines' normal.
fn bands(bar: &ImageBar, width: u32, height: u32) -> (Vec<Vec<BandPixel>>, f64) {
    let d = bar.to - bar.from;
    let rows = d.y.abs() >= d.x.abs();
    // (u, v): u along a scanline, v across them (the scanline's index).
    let to_uv = |p: DVec2| if rows { p } else { DVec2::new(p.y, p.x) };
    let (from, to) = (to_uv(bar.from), to_uv(bar.to));
    let (u_len, v_len) = if rows {
        (width, height)
    } else {
        (height, width)
    };
    let Some(dir) = (to - from).try_normalize() else {
        return (Vec::new(), 1.0);
    };
    let cos = dir.y.abs();
    let slope = dir.x / dir.y;
    let half_extent = 0.5 * bar.width / cos;
    // Within one pixel's span across the scanlines the bar's centre moves
    // by up to half the slope either way, on top of the pixel's own half.
    let clear_beyond = half_extent + 0.5 * (1.0 + slope.abs()) + 0.25;
    let reach = half_extent + BAND_MARGIN_PX;
    let (v_lo, v_hi) = (from.y.min(to.y), from.y.max(to.y));
    let mut bands = Vec::new();
    let first = (v_lo - 0.5).ceil() as i64;
    let last = (v_hi - 0.5).floor() as i64;
    for v in first..=last {
        let centre = from.x + (v as f64 + 0.5 - from.y) * slope;
        let u_first = (centre - reach - 0.5).ceil() as i64;
        let u_last = (centre + reach - 0.5).floor() as i64;
        if v < 0 || v >= i64::from(v_len) || u_first < 0 || u_last >= i64::from(u_len) {
            continue;
        }
        let band = (u_first..=u_last)
            .map(|u| {
                let clear = (u as f64 + 0.5 - centre).abs() > clear_beyond;
                let (x, y) = if rows { (u, v) } else { (v, u) };
                BandPixel {
                    x: x as u32,
                    y: y as u32,
                    clear,
                }
            })
            .collect();
        bands.push(band);
    }
    (bands, cos)
}

impl GaugedBar {
    /// The mean width of the bar over its bands in `image`.
    fn width_in(&self, image: &RgbaImage) -> f64 {
        let span = self.bar - self.behind;
        let total: f64 = self
            .bands
            .iter()
            .flatten()
            .map(|p| {
                let l = linear_luminance(image.get_pixel(p.x, p.y));
                ((l - self.behind) / span).clamp(0.0, 1.0)
            })
            .sum();
        total * self.cos / self.bands.len().max(1) as f64
    }
}

impl BarGauge {
    /// Reads the bars' luminances from `reference` and measures the
    /// reference's own widths. Fails when there is no bar, a bar has no
    /// band inside the image, or the reference shows a bar too close in
    /// luminance to what is behind it.
    pub fn new(reference: &RgbaImage, bars: &[ImageBar]) -> Result<BarGauge, BarWidthError> {
        if bars.is_empty() {
            return Err(BarWidthError::NoBars);
        }
        let (width, height) = reference.dimensions();
        let mut gauged = Vec::with_capacity(bars.len());
        for (index, bar) in bars.iter().enumerate() {
            let (bands, cos) = bands(bar, width, height);
            if bands.is_empty() {
                return Err(BarWidthError::OutsideImage {
                    bar: index,
                    width,
                    height,
                });
            }
            let luminance = |p: &BandPixel| linear_luminance(reference.get_pixel(p.x, p.y));
            let behind = median(
                bands
                    .iter()
                    .flatten()
                    .filter(|p| p.clear)
                    .map(luminance)
                    .collect(),
            );
            let excess: f64 = bands.iter().flatten().map(|p| luminance(p) - behind).sum();
            let extent = bar.width / cos;
            let bar_luminance = behind + excess / (extent * bands.len() as f64);
            let contrast = (bar_luminance - behind).abs();
            if contrast.is_nan() || contrast < MIN_CONTRAST {
                return Err(BarWidthError::LowContrast {
                    bar: index,
                    bar_luminance,
                    behind_luminance: behind,
                });
            }
            let mut g = GaugedBar {
                bands,
                cos,
                behind,
                bar: bar_luminance,
                reference_width: 0.0,
            };
            g.reference_width = g.width_in(reference);
            gauged.push(g);
        }
        Ok(BarGauge {
            width,
            height,
            bars: gauged,
        })
    }

    /// Each bar's width in the reference, in pixels (its mean over the
    /// bar's scanlines).
    pub fn reference_widths(&self) -> Vec<f64> {
        self.bars.iter().map(|b| b.reference_width).collect()
    }

    /// Each bar's width in `image`, in pixels.
    pub fn widths(&self, image: &RgbaImage) -> Result<Vec<f64>, BarWidthError> {
        if image.dimensions() != (self.width, self.height) {
            return Err(BarWidthError::SizeMismatch {
                width: image.width(),
                height: image.height(),
                reference_width: self.width,
                reference_height: self.height,
            });
        }
        Ok(self.bars.iter().map(|b| b.width_in(image)).collect())
    }

    /// The bar width error of `image`: the mean over the bars of its
    /// width less the reference's, in pixels (see the module).
    pub fn width_error(&self, image: &RgbaImage) -> Result<f64, BarWidthError> {
        let widths = self.widths(image)?;
        let sum: f64 = widths
            .iter()
            .zip(&self.bars)
            .map(|(w, b)| w - b.reference_width)
            .sum();
        Ok(sum / self.bars.len().max(1) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::super::pixels::linear_to_srgb;
    use super::*;

    const SIZE: (u32, u32) = (96, 64);
    /// Linear luminances: a bright bar on a dark wall.
    const WALL: f32 = 0.02;
    const BRIGHT: f32 = 0.6;

    /// A straight bar `width` pixels wide through `a` and `b` (running on
    /// past them to the image's borders), antialiased with `n`×`n` samples
    /// per pixel (1: one sample at the centre, aliased), blended in linear
    /// light between `behind` and `bar`.
    fn draw(a: DVec2, b: DVec2, width: f64, n: u32, behind: f32, bar: f32) -> RgbaImage {
        let dir = (b - a).normalize();
        RgbaImage::from_fn(SIZE.0, SIZE.1, |x, y| {
            let mut inside = 0;
            for sy in 0..n {
                for sx in 0..n {
                    let p = DVec2::new(
                        f64::from(x) + (f64::from(sx) + 0.5) / f64::from(n),
                        f64::from(y) + (f64::from(sy) + 0.5) / f64::from(n),
                    );
                    if dir.perp_dot(p - a).abs() <= 0.5 * width {
                        inside += 1;
                    }
                }
            }
            let coverage = inside as f32 / (n * n) as f32;
            let v = linear_to_srgb(behind + (bar - behind) * coverage);
            image::Rgba([v, v, v, 255])
        })
    }

    fn gauge_and_error(a: DVec2, b: DVec2, reference: f64, test: f64, n: u32) -> f64 {
        let bar = ImageBar {
            from: a,
            to: b,
            width: reference,
        };
        let gauge = BarGauge::new(&draw(a, b, reference, 8, WALL, BRIGHT), &[bar]).expect("gauge");
        gauge
            .width_error(&draw(a, b, test, n, WALL, BRIGHT))
            .expect("same size")
    }

    /// Drawn thinner by half a pixel, a bar measures half a pixel thinner;
    /// wider, wider; the reference itself, exactly as wide. Rows measure a
    /// steep bar, columns a flat one; both come out alike.
    #[test]
    fn a_thinner_bar_measures_thinner_by_the_difference() {
        let steep = (DVec2::new(30.0, 12.0), DVec2::new(41.0, 52.0));
        let flat = (DVec2::new(14.0, 40.0), DVec2::new(80.0, 22.0));
        for (a, b) in [steep, flat] {
            let thinner = gauge_and_error(a, b, 2.0, 1.5, 8);
            assert!((thinner + 0.5).abs() < 0.05, "{a} {b}: {thinner}");
            let wider = gauge_and_error(a, b, 1.4, 2.0, 8);
            assert!((wider - 0.6).abs() < 0.05, "{a} {b}: {wider}");
            assert_eq!(gauge_and_error(a, b, 2.6, 2.6, 8), 0.0);
        }
    }

    /// Aliasing moves each scanline's width by up to a pixel, but not the
    /// mean: the measure is of width, not of smoothness.
    #[test]
    fn an_aliased_bar_keeps_its_width_on_average() {
        let error = gauge_and_error(DVec2::new(30.0, 12.0), DVec2::new(41.0, 52.0), 1.3, 1.3, 1);
        assert!(error.abs() < 0.1, "{error}");
    }

    /// A dark bar on a bright wall is measured as well as the reverse.
    #[test]
    fn a_dark_bar_on_a_bright_wall_is_measured_alike() {
        let (a, b) = (DVec2::new(60.0, 8.0), DVec2::new(50.0, 56.0));
        let bar = ImageBar {
            from: a,
            to: b,
            width: 3.0,
        };
        let gauge = BarGauge::new(&draw(a, b, 3.0, 8, BRIGHT, WALL), &[bar]).expect("gauge");
        let widths = gauge
            .widths(&draw(a, b, 2.0, 8, BRIGHT, WALL))
            .expect("same size");
        assert!((widths[0] - 2.0).abs() < 0.05, "{widths:?}");
        assert!((gauge.reference_widths()[0] - 3.0).abs() < 0.05);
    }

    #[test]
    fn unmeasurable_bars_are_errors() {
        let (a, b) = (DVec2::new(30.0, 12.0), DVec2::new(41.0, 52.0));
        let image = draw(a, b, 2.0, 8, WALL, BRIGHT);
        let bar = ImageBar {
            from: a,
            to: b,
            width: 2.0,
        };
        assert_eq!(
            BarGauge::new(&image, &[]).unwrap_err(),
            BarWidthError::NoBars
        );
        let off = ImageBar {
            from: DVec2::new(200.0, 12.0),
            to: DVec2::new(211.0, 52.0),
            ..bar
        };
        assert!(matches!(
            BarGauge::new(&image, &[bar, off]),
            Err(BarWidthError::OutsideImage { bar: 1, .. })
        ));
        let flat = draw(a, b, 2.0, 8, WALL, WALL + 0.01);
        let err = BarGauge::new(&flat, &[bar]).unwrap_err();
        assert!(
            matches!(err, BarWidthError::LowContrast { bar: 0, .. }),
            "{err}"
        );
        assert!(!err.to_string().contains('\n'));
        let gauge = BarGauge::new(&image, &[bar]).expect("gauge");
        assert!(matches!(
            gauge.width_error(&RgbaImage::new(8, 8)),
            Err(BarWidthError::SizeMismatch { .. })
        ));
    }
}
