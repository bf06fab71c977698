//! The motion bench's animated crop strip (`motion-SCENE.png`): per frame
//! of the camera path, the same crop of the reference and of every run
//! side by side, magnified with nearest-neighbour sampling under a label
//! row, as an animated PNG. APNG rather than GIF: a GIF's 256-colour
//! palette dithers exactly the edge gradients the strip is there to show.

use super::plot::{FAMILY, load_font, plot_error};
use crate::{Error, Result};
use image::{RgbImage, RgbaImage, imageops};
use plotters::prelude::*;
use std::path::Path;

/// Target size of a magnified tile, in pixels.
const TILE: u32 = 160;
/// Space between tiles.
const GAP: u32 = 8;
/// Height of the label row.
const LABEL_H: u32 = 24;
/// Frames per second of the animation.
const FPS: u16 = 12;

/// One labelled column of the strip: a crop per frame.
pub(crate) struct Column<'a> {
    /// The label above it.
    pub(crate) label: String,
    /// Its crop in each frame, all of one size.
    pub(crate) crops: &'a [RgbaImage],
}

/// The strip's frames: per frame, the columns' crops magnified side by
/// side under their labels. `None` when there is nothing to draw or the
/// columns differ in frame count or crop size.
pub(crate) fn strip_frames(columns: &[Column]) -> Result<Option<Vec<RgbImage>>> {
    let Some(first) = columns.first().and_then(|c| c.crops.first()) else {
        return Ok(None);
    };
    let (cw, ch) = first.dimensions();
    let frames = columns[0].crops.len();
    if columns
        .iter()
        .any(|c| c.crops.len() != frames || c.crops.iter().any(|i| i.dimensions() != (cw, ch)))
    {
        return Ok(None);
    }
    load_font()?;
    let k = (TILE / cw.max(ch).max(1)).max(1);
    let (tw, th) = (cw * k, ch * k);
    let width = GAP + columns.len() as u32 * (tw + GAP);
    let height = LABEL_H + th + GAP;
    // The labels once; each frame copies them and adds its tiles.
    let mut labels = RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
    {
        let root = BitMapBackend::with_buffer(&mut labels, (width, height)).into_drawing_area();
        for (i, column) in columns.iter().enumerate() {
            let x = GAP + i as u32 * (tw + GAP);
            root.draw(&Text::new(
                column.label.clone(),
                (x as i32, 4),
                (FAMILY, 14).into_font().color(&BLACK),
            ))
            .map_err(|e| plot_error("the motion strip", e))?;
        }
        root.present()
            .map_err(|e| plot_error("the motion strip", e))?;
    }
    let mut out = Vec::with_capacity(frames);
    for f in 0..frames {
        let mut canvas = labels.clone();
        for (i, column) in columns.iter().enumerate() {
            let crop = &column.crops[f];
            let rgb = RgbImage::from_fn(cw, ch, |x, y| {
                let p = crop.get_pixel(x, y);
                image::Rgb([p[0], p[1], p[2]])
            });
            let tile = imageops::resize(&rgb, tw, th, imageops::FilterType::Nearest);
            let x = GAP + i as u32 * (tw + GAP);
            imageops::replace(&mut canvas, &tile, i64::from(x), i64::from(LABEL_H));
        }
        out.push(canvas);
    }
    Ok(Some(out))
}

/// Write `frames` (all of one size) as an animated PNG that loops, at
/// [`FPS`] frames per second.
pub(crate) fn write_apng(frames: &[RgbImage], path: &Path) -> Result<()> {
    let Some(first) = frames.first() else {
        return Err(Error::invalid(format!(
            "{}: an animation needs at least one frame",
            path.display()
        )));
    };
    let (w, h) = first.dimensions();
    let encode = |e: png::EncodingError| {
        Error::invalid(format!("writing the animation {}: {e}", path.display()))
    };
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .set_animated(frames.len() as u32, 0)
        .map_err(encode)?;
    encoder.set_frame_delay(1, FPS).map_err(encode)?;
    let mut writer = encoder.write_header().map_err(encode)?;
    for frame in frames {
        if frame.dimensions() != (w, h) {
            return Err(Error::invalid(format!(
                "{}: the animation's frames differ in size",
                path.display()
            )));
        }
        writer.write_image_data(frame.as_raw()).map_err(encode)?;
    }
    writer.finish().map_err(encode)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strip_is_an_animated_png_with_a_frame_per_path_frame() {
        let crops: Vec<RgbaImage> = (0..3u8)
            .map(|k| RgbaImage::from_pixel(4, 4, image::Rgba([k * 80, 0, 0, 255])))
            .collect();
        let columns = [
            Column {
                label: "reference".into(),
                crops: &crops,
            },
            Column {
                label: "none".into(),
                crops: &crops,
            },
        ];
        let frames = strip_frames(&columns).unwrap().unwrap();
        assert_eq!(frames.len(), 3);
        // Each frame shows its own crop, magnified, below the labels.
        assert_eq!(frames[2].get_pixel(GAP + 1, LABEL_H + 1)[0], 160);
        assert_eq!(frames[0].get_pixel(GAP + 1, LABEL_H + 1)[0], 0);
        let dir = std::env::temp_dir().join(format!("dmsaa-apng-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("strip.png");
        write_apng(&frames, &path).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        let control = reader.info().animation_control.unwrap();
        assert_eq!((control.num_frames, control.num_plays), (3, 0));
        std::fs::remove_dir_all(&dir).unwrap();
        // Mismatched columns draw nothing.
        let short = &crops[..2];
        let bad = [
            Column {
                label: "a".into(),
                crops: &crops,
            },
            Column {
                label: "b".into(),
                crops: short,
            },
        ];
        assert!(strip_frames(&bad).unwrap().is_none());
    }
}
