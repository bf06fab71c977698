//! A finished bench ([`BenchOutput`]) and the measured images written
//! one file each.

use crate::{Error, Result};
use image::{RgbImage, RgbaImage};
use std::path::Path;

use super::report::Report;

/// A finished bench: the report and the images it measured.
#[derive(Clone, Debug)]
pub struct BenchOutput {
    /// The report.
    pub report: Report,
    /// Each scene's reference image, in scene order.
    pub references: Vec<(String, RgbaImage)>,
    /// The final image of each run, parallel to [`Report::runs`] (with
    /// `--motion`, its frame at the scene's own camera).
    pub images: Vec<RgbaImage>,
    /// With `--motion`: per scene, the animated crop strip's frames.
    pub animations: Vec<(String, Vec<RgbImage>)>,
}

/// The file name of a scene's animated crop strip.
pub fn motion_strip_name(scene: &str) -> String {
    format!("motion-{}.png", file_stem(scene))
}

/// A file-name-safe form of a scene spec or method entry.
pub(super) fn file_stem(s: &str) -> String {
    let stem = s.rsplit(['/', '\\']).next().unwrap_or(s);
    stem.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Write every measured image into `dir/images/`: `SCENE-ssaa.png` (the
/// reference) and `SCENE-METHOD-Nx.png` per run, for looking at closely.
pub fn write_images(output: &BenchOutput, dir: &Path) -> Result<()> {
    let dir = dir.join("images");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let save = |img: &RgbaImage, name: String| {
        let path = dir.join(name);
        img.save_with_format(&path, image::ImageFormat::Png)
            .map_err(|source| Error::Image { path, source })
    };
    for (scene, reference) in &output.references {
        save(reference, format!("{}-ssaa.png", file_stem(scene)))?;
    }
    for (run, img) in output.report.runs.iter().zip(&output.images) {
        save(
            img,
            format!(
                "{}-{}-{}x.png",
                file_stem(&run.scene),
                file_stem(&run.method),
                run.samples
            ),
        )?;
    }
    Ok(())
}
