//! The crop figures. `crops.png`: per scene, an overview of the reference
//! with the crop marked, then the same crop of the reference and of every
//! run side by side, magnified with nearest-neighbour sampling and
//! labelled, like a paper's figure. The first run's side-by-side
//! ([`side_by_side`]): every run's whole frame above its magnified crop.
//!
//! The crop is chosen automatically as the window where the methods'
//! errors against the reference differ most (the sum over its pixels of
//! the largest minus the smallest absolute luminance error among the runs),
//! with the reference's own edge detail as a small tie-breaker.

use super::output::BenchOutput;
use super::plot::{FAMILY, load_font, plot_error, save_rgb};
use crate::Result;
use crate::compare::luminance;
use image::{RgbImage, RgbaImage, imageops};
use plotters::prelude::*;
use std::path::Path;

/// Target size of a magnified tile, in pixels.
const TILE: u32 = 176;
/// Space between tiles.
const GAP: u32 = 10;
/// Height of a row's title.
const TITLE_H: u32 = 28;
/// Height of the two label lines above each tile.
const LABEL_H: u32 = 38;

/// The crop's side for a `width`×`height` image: a quarter of the shorter
/// side, between 8 and 64 pixels (never more than the image).
pub(crate) fn crop_side(width: u32, height: u32) -> u32 {
    (width.min(height) / 4)
        .clamp(8, 64)
        .min(width)
        .min(height)
        .max(1)
}

/// The top-left corner of the `side`×`side` window of most error spread
/// among `runs` against `reference`.
pub(crate) fn choose_crop(reference: &RgbaImage, runs: &[&RgbaImage], side: u32) -> (u32, u32) {
    let (w, h) = reference.dimensions();
    if side >= w && side >= h {
        return (0, 0);
    }
    let lum = |img: &RgbaImage| -> Vec<f32> { img.pixels().map(luminance).collect() };
    let l_ref = lum(reference);
    let l_runs: Vec<Vec<f32>> = runs
        .iter()
        .filter(|r| r.dimensions() == (w, h))
        .map(|r| lum(r))
        .collect();
    let (wu, hu) = (w as usize, h as usize);
    let mut score = vec![0f64; wu * hu];
    for y in 0..hu {
        for x in 0..wu {
            let i = y * wu + x;
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for l in &l_runs {
                let e = (l[i] - l_ref[i]).abs();
                lo = lo.min(e);
                hi = hi.max(e);
            }
            let spread = if l_runs.is_empty() { 0.0 } else { hi - lo };
            let gx = if x + 1 < wu {
                (l_ref[i + 1] - l_ref[i]).abs()
            } else {
                0.0
            };
            let gy = if y + 1 < hu {
                (l_ref[i + wu] - l_ref[i]).abs()
            } else {
                0.0
            };
            score[i] = spread as f64 + 0.1 * (gx + gy) as f64;
        }
    }
    // Summed-area table, one row and column of zeros in front.
    let mut sat = vec![0f64; (wu + 1) * (hu + 1)];
    for y in 0..hu {
        let mut row = 0.0;
        for x in 0..wu {
            row += score[y * wu + x];
            sat[(y + 1) * (wu + 1) + x + 1] = sat[y * (wu + 1) + x + 1] + row;
        }
    }
    let (sw, sh) = (side.min(w) as usize, side.min(h) as usize);
    let mut best = (0usize, 0usize, f64::NEG_INFINITY);
    for y in 0..=hu - sh {
        for x in 0..=wu - sw {
            let s = sat[(y + sh) * (wu + 1) + x + sw]
                - sat[y * (wu + 1) + x + sw]
                - sat[(y + sh) * (wu + 1) + x]
                + sat[y * (wu + 1) + x];
            if s > best.2 {
                best = (x, y, s);
            }
        }
    }
    (best.0 as u32, best.1 as u32)
}

fn rgb(img: &RgbaImage) -> RgbImage {
    RgbImage::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get_pixel(x, y);
        image::Rgb([p[0], p[1], p[2]])
    })
}

/// One tile: its image, label lines and where it goes.
struct Tile {
    image: RgbImage,
    lines: [String; 2],
    x: u32,
    y: u32,
}

/// Draw `crops.png` for a finished bench.
pub(crate) fn crops(output: &BenchOutput, path: &Path) -> Result<()> {
    load_font()?;
    let report = &output.report;
    let mut tiles: Vec<Tile> = Vec::new();
    let mut titles: Vec<(String, u32)> = Vec::new();
    let mut marks: Vec<(u32, u32, u32, u32)> = Vec::new();
    let mut width = GAP;
    let mut y = GAP;
    for (scene, reference) in &output.references {
        let indices: Vec<usize> = report
            .runs
            .iter()
            .enumerate()
            .filter(|(_, r)| &r.scene == scene)
            .map(|(i, _)| i)
            .collect();
        let images: Vec<&RgbaImage> = indices
            .iter()
            .filter_map(|&i| output.images.get(i))
            .collect();
        let (w, h) = reference.dimensions();
        let side = crop_side(w, h);
        let (cx, cy) = choose_crop(reference, &images, side);
        let (sw, sh) = (side.min(w), side.min(h));
        let k = (TILE / sw.max(sh)).max(1);
        let (tw, th) = (sw * k, sh * k);
        titles.push((
            format!("{scene}: {sw}x{sh} crop at ({cx}, {cy}), magnified {k}x"),
            y,
        ));
        let row_y = y + TITLE_H + LABEL_H;
        // The overview: the whole reference at the tiles' height.
        let ow = ((th as f64 * w as f64 / h as f64).round() as u32).max(1);
        let overview = imageops::resize(&rgb(reference), ow, th, imageops::FilterType::Triangle);
        let scale = (ow as f64 / w as f64, th as f64 / h as f64);
        marks.push((
            GAP + (cx as f64 * scale.0).floor() as u32,
            row_y + (cy as f64 * scale.1).floor() as u32,
            ((sw as f64 * scale.0).ceil() as u32).max(2),
            ((sh as f64 * scale.1).ceil() as u32).max(2),
        ));
        let mut x = GAP;
        tiles.push(Tile {
            image: overview,
            lines: [
                "reference (ssaa 16 spp)".into(),
                "crop marked in red".into(),
            ],
            x,
            y: row_y,
        });
        x += ow + GAP;
        let crop = |img: &RgbaImage| {
            let c = imageops::crop_imm(img, cx, cy, sw, sh).to_image();
            imageops::resize(&rgb(&c), tw, th, imageops::FilterType::Nearest)
        };
        tiles.push(Tile {
            image: crop(reference),
            lines: [
                "ssaa (reference)".into(),
                format!("{} spp", report.reference.spp),
            ],
            x,
            y: row_y,
        });
        x += tw + GAP;
        for &i in &indices {
            let (Some(run), Some(img)) = (report.runs.get(i), output.images.get(i)) else {
                continue;
            };
            if img.dimensions() != (w, h) {
                continue;
            }
            let name = if run.samples > 1 {
                format!("{} ({}x)", run.method, run.samples)
            } else {
                run.method.clone()
            };
            tiles.push(Tile {
                image: crop(img),
                lines: [
                    name,
                    format!("FLIP {:.4} · halo {}", run.flip_mean, run.halo_pixels),
                ],
                x,
                y: row_y,
            });
            x += tw + GAP;
        }
        width = width.max(x);
        y = row_y + th + GAP * 2;
    }
    Figure {
        tiles,
        titles,
        marks,
    }
    .save(width, y.max(GAP * 2), "crops.png", path)
}

/// Widest an overview tile of [`side_by_side`] gets.
const OVERVIEW_W: u32 = 320;

/// The first run's figure, per scene: a column for the reference and for
/// each run, the whole frame on top (the crop marked in red) and below it
/// the crop of most error spread ([`choose_crop`]), magnified with
/// nearest-neighbour sampling; each run labelled with its FLIP against the
/// reference and its frame time.
pub(crate) fn side_by_side(output: &BenchOutput, path: &Path) -> Result<()> {
    load_font()?;
    let report = &output.report;
    let mut figure = Figure {
        tiles: Vec::new(),
        titles: Vec::new(),
        marks: Vec::new(),
    };
    let mut width = GAP;
    let mut y = GAP;
    for (scene, reference) in &output.references {
        let (w, h) = reference.dimensions();
        let runs: Vec<(&super::report::Run, &RgbaImage)> = report
            .runs
            .iter()
            .zip(&output.images)
            .filter(|(r, img)| &r.scene == scene && img.dimensions() == (w, h))
            .collect();
        let images: Vec<&RgbaImage> = runs.iter().map(|(_, img)| *img).collect();
        let side = crop_side(w, h);
        let (cx, cy) = choose_crop(reference, &images, side);
        let (sw, sh) = (side.min(w), side.min(h));
        // The overview at most OVERVIEW_W wide, never enlarged.
        let ow = w.min(OVERVIEW_W);
        let oh = ((ow as f64 * h as f64 / w as f64).round() as u32).max(1);
        let k = (ow / sw.max(sh)).max(1);
        let (tw, th) = (sw * k, sh * k);
        let column = ow.max(tw) + GAP;
        figure.titles.push((
            format!(
                "{scene}, {w}x{h}: each whole frame, and its {sw}x{sh} crop at ({cx}, {cy}) where the methods differ most, magnified {k}x"
            ),
            y,
        ));
        let overview_y = y + TITLE_H + LABEL_H;
        let crop_y = overview_y + oh + GAP + LABEL_H;
        let scale = (ow as f64 / w as f64, oh as f64 / h as f64);
        let columns = std::iter::once((
            [
                "ssaa (reference)".to_string(),
                format!("{} spp", report.reference.spp),
            ],
            reference,
        ))
        .chain(runs.iter().map(|(run, img)| {
            let name = if run.samples > 1 {
                format!("{} ({}x)", run.method, run.samples)
            } else {
                run.method.clone()
            };
            (
                [
                    name,
                    format!("FLIP {:.4} · {:.1} ms", run.flip_mean, run.ms_total),
                ],
                *img,
            )
        }));
        let mut x = GAP;
        for (lines, img) in columns {
            let frame = if ow == w {
                rgb(img)
            } else {
                imageops::resize(&rgb(img), ow, oh, imageops::FilterType::Triangle)
            };
            figure.marks.push((
                x + (cx as f64 * scale.0).floor() as u32,
                overview_y + (cy as f64 * scale.1).floor() as u32,
                ((sw as f64 * scale.0).ceil() as u32).max(2),
                ((sh as f64 * scale.1).ceil() as u32).max(2),
            ));
            figure.tiles.push(Tile {
                image: frame,
                lines,
                x,
                y: overview_y,
            });
            let crop = imageops::crop_imm(img, cx, cy, sw, sh).to_image();
            figure.tiles.push(Tile {
                image: imageops::resize(&rgb(&crop), tw, th, imageops::FilterType::Nearest),
                lines: [format!("crop, {k}x"), String::new()],
                x,
                y: crop_y,
            });
            x += column;
        }
        width = width.max(x);
        y = crop_y + th + GAP * 2;
    }
    figure.save(width, y.max(GAP * 2), "the side-by-side", path)
}

/// Tiles with their labels, row titles and red marks, drawn on white.
struct Figure {
    tiles: Vec<Tile>,
    /// A title and the top of its row.
    titles: Vec<(String, u32)>,
    /// Rectangles `(x, y, w, h)` outlined in red (where a crop was taken).
    marks: Vec<(u32, u32, u32, u32)>,
}

impl Figure {
    /// Draw the figure on a `width`×`height` canvas and save it as a PNG
    /// (`what` names it in errors).
    fn save(&self, width: u32, height: u32, what: &str, path: &Path) -> Result<()> {
        let Figure {
            tiles,
            titles,
            marks,
        } = self;
        let mut canvas = RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
        for t in tiles {
            imageops::replace(&mut canvas, &t.image, t.x as i64, t.y as i64);
        }
        {
            let err = |e| plot_error(what, e);
            let root = BitMapBackend::with_buffer(&mut canvas, (width, height)).into_drawing_area();
            for (title, ty) in titles {
                root.draw(&Text::new(
                    title.clone(),
                    (GAP as i32, *ty as i32 + 6),
                    (FAMILY, 18).into_font().color(&BLACK),
                ))
                .map_err(err)?;
            }
            for t in tiles {
                let ly = t.y as i32 - LABEL_H as i32;
                root.draw(&Text::new(
                    t.lines[0].clone(),
                    (t.x as i32, ly + 2),
                    (FAMILY, 15).into_font().color(&BLACK),
                ))
                .map_err(err)?;
                root.draw(&Text::new(
                    t.lines[1].clone(),
                    (t.x as i32, ly + 20),
                    (FAMILY, 13).into_font().color(&RGBColor(90, 90, 90)),
                ))
                .map_err(err)?;
                root.draw(&Rectangle::new(
                    [
                        (t.x as i32 - 1, t.y as i32 - 1),
                        (
                            (t.x + t.image.width()) as i32,
                            (t.y + t.image.height()) as i32,
                        ),
                    ],
                    RGBColor(160, 160, 160).stroke_width(1),
                ))
                .map_err(err)?;
            }
            for &(mx, my, mw, mh) in marks {
                root.draw(&Rectangle::new(
                    [(mx as i32, my as i32), ((mx + mw) as i32, (my + mh) as i32)],
                    RGBColor(230, 30, 30).stroke_width(2),
                ))
                .map_err(err)?;
            }
            root.present().map_err(err)?;
        }
        save_rgb(canvas.into_raw(), width, height, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_crop_lands_where_methods_disagree() {
        let reference = RgbaImage::from_pixel(64, 40, image::Rgba([100, 100, 100, 255]));
        let mut a = reference.clone();
        for y in 20..28 {
            for x in 40..48 {
                a.put_pixel(x, y, image::Rgba([255, 255, 255, 255]));
            }
        }
        let b = reference.clone();
        let side = crop_side(64, 40);
        assert_eq!(side, 10);
        let (x, y) = choose_crop(&reference, &[&a, &b], side);
        assert!(
            (38..=40).contains(&x) && (18..=20).contains(&y),
            "({x}, {y})"
        );
        assert_eq!(choose_crop(&reference, &[], 64), (0, 0));
    }
}
