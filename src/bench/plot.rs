//! `error_vs_time.png`: FLIP mean against frame time, one panel per scene,
//! the Pareto front marked, every point labelled. Drawn with plotters into
//! an RGB buffer, saved with `image`.

use super::report::{Report, Run, pareto_front};
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Where the plots' font is read from, unless `DEFERRED_MSAA_FONT` names another.
pub(crate) const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// The family name the font is registered under.
pub(crate) const FAMILY: &str = "sans-serif";

/// Read and register the font once per process (plotters keeps it for good).
pub(crate) fn load_font() -> Result<()> {
    static LOADED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    LOADED
        .get_or_init(|| {
            let path = std::env::var_os("DEFERRED_MSAA_FONT")
                .map(std::path::PathBuf::from)
                .unwrap_or_else(|| DEFAULT_FONT.into());
            let bytes = std::fs::read(&path).map_err(|e| {
                format!(
                    "the bench plots need a TrueType font and {} cannot be read ({e}); \
                     install Debian's fonts-dejavu-core or set DEFERRED_MSAA_FONT to a .ttf file",
                    path.display()
                )
            })?;
            // plotters keeps registered fonts for the life of the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font(FAMILY, FontStyle::Normal, bytes)
                .map_err(|_| format!("{} is not a font plotters can read", path.display()))
        })
        .clone()
        .map_err(Error::invalid)
}

/// A plotters error as the crate's error.
pub(crate) fn plot_error(what: &str, e: impl std::fmt::Display) -> Error {
    Error::invalid(format!("drawing {what}: {e}"))
}

/// Save an RGB buffer as a PNG.
pub(crate) fn save_rgb(buffer: Vec<u8>, width: u32, height: u32, path: &Path) -> Result<()> {
    let img = image::RgbImage::from_raw(width, height, buffer).ok_or_else(|| {
        Error::invalid(format!(
            "{}: the plot buffer does not hold {width}x{height} pixels",
            path.display()
        ))
    })?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|source| Error::Image {
            path: path.to_path_buf(),
            source,
        })
}

/// Panel size of one scene.
const PANEL: (u32, u32) = (1000, 560);

/// Draw `error_vs_time.png`.
pub(crate) fn error_vs_time(report: &Report, path: &Path) -> Result<()> {
    against_time(report, path, &FLIP_MEAN)
}

/// Draw `temporal_error_vs_time.png`: the motion bench's temporal error
/// against frame time, per scene.
pub(crate) fn temporal_error_vs_time(report: &Report, path: &Path) -> Result<()> {
    against_time(report, path, &TEMPORAL_ERROR)
}

/// A measure plotted against frame time.
struct Measure {
    /// What the caption calls it.
    name: &'static str,
    /// The y axis.
    y_desc: &'static str,
    /// Its value for a run (not finite: no point).
    value: fn(&Run) -> f64,
}

const FLIP_MEAN: Measure = Measure {
    name: "error",
    y_desc: "FLIP mean against ssaa (lower is better)",
    value: |r| r.flip_mean,
};

const TEMPORAL_ERROR: Measure = Measure {
    name: "temporal error",
    y_desc: "temporal error against ssaa (lower is better)",
    value: |r| r.motion.as_ref().map_or(f64::NAN, |m| m.temporal_error),
};

fn against_time(report: &Report, path: &Path, measure: &Measure) -> Result<()> {
    load_font()?;
    let scenes = report.scenes();
    let (w, h) = (PANEL.0, PANEL.1 * scenes.len().max(1) as u32);
    let mut buffer = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error("the plot", e))?;
        let panels = root.split_evenly((scenes.len().max(1), 1));
        for (area, scene) in panels.iter().zip(&scenes) {
            let runs: Vec<&Run> = report.runs_of(scene).collect();
            draw_panel(area, report, scene, &runs, measure)?;
        }
        root.present().map_err(|e| plot_error("the plot", e))?;
    }
    save_rgb(buffer, w, h, path)
}

/// A pixel rectangle, for keeping labels apart.
#[derive(Clone, Copy)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    fn overlaps(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    report: &Report,
    scene: &str,
    runs: &[&Run],
    measure: &Measure,
) -> Result<()> {
    let err = |e| plot_error("the error-against-time plot", e);
    let points: Vec<(f64, f64)> = runs
        .iter()
        .map(|r| (r.ms_total, (measure.value)(r)))
        .collect();
    let front = pareto_front(&points);
    let finite = || {
        points
            .iter()
            .filter(|(t, e)| t.is_finite() && e.is_finite())
    };
    let t_max = finite().map(|p| p.0).fold(0.0, f64::max).max(1e-3);
    let e_max = finite().map(|p| p.1).fold(0.0, f64::max).max(1e-4);
    let several_counts = {
        let mut counts: Vec<u32> = runs
            .iter()
            .filter(|r| r.samples > 1)
            .map(|r| r.samples)
            .collect();
        counts.dedup();
        counts.len() > 1
    };
    let label_of = |r: &Run| {
        if several_counts && r.samples > 1 {
            format!("{} {}x", r.method, r.samples)
        } else {
            r.method.clone()
        }
    };
    let max_samples = runs.iter().map(|r| r.samples).max().unwrap_or(1);
    let size = runs.first().map_or(String::new(), |r| {
        format!("{}x{}, up to {max_samples}x MSAA", r.width, r.height)
    });
    let timer = runs.first().map_or("", |r| r.timer.as_str());
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "{scene}: {} against frame time ({size}, {})",
                measure.name, report.renderer
            ),
            (FAMILY, 20),
        )
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(0.0..t_max * 1.18, 0.0..e_max * 1.18)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(format!("frame time, ms (median, {timer})"))
        .y_desc(measure.y_desc)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;

    // The Pareto front as a staircase through its points.
    let mut on_front: Vec<(f64, f64)> = points
        .iter()
        .zip(&front)
        .filter(|(_, f)| **f)
        .map(|(p, _)| *p)
        .collect();
    on_front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let front_colour = RGBColor(200, 40, 40);
    if on_front.len() > 1 {
        let mut stairs = Vec::new();
        for pair in on_front.windows(2) {
            stairs.push(pair[0]);
            stairs.push((pair[1].0, pair[0].1));
        }
        if let Some(last) = on_front.last() {
            stairs.push(*last);
        }
        chart
            .draw_series(std::iter::once(PathElement::new(
                stairs,
                ShapeStyle::from(&front_colour.mix(0.6)).stroke_width(2),
            )))
            .map_err(err)?;
    }
    let other = RGBColor(40, 90, 170);
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    chart
        .draw_series(
            points
                .iter()
                .zip(&front)
                .filter(|(p, f)| finite(p) && !**f)
                .map(|(p, _)| Circle::new(*p, 5, other.stroke_width(2))),
        )
        .map_err(err)?
        .label("dominated: another method is as fast and as good")
        .legend(move |(x, y)| Circle::new((x + 9, y), 5, other.stroke_width(2)));
    chart
        .draw_series(
            points
                .iter()
                .zip(&front)
                .filter(|(p, f)| finite(p) && **f)
                .map(|(p, _)| Circle::new(*p, 6, front_colour.filled())),
        )
        .map_err(err)?
        .label("on the Pareto front")
        .legend(move |(x, y)| Circle::new((x + 9, y), 6, front_colour.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .draw()
        .map_err(err)?;

    // Labels beside their points, placed greedily where they overlap
    // neither another label nor a point.
    let base = area.get_base_pixel();
    let font_size = 14;
    let mut taken: Vec<Rect> = points
        .iter()
        .map(|p| {
            let (x, y) = chart.backend_coord(p);
            Rect {
                x0: x - 6,
                y0: y - 6,
                x1: x + 6,
                y1: y + 6,
            }
        })
        .collect();
    let (area_w, area_h) = area.dim_in_pixel();
    for (i, run) in runs.iter().enumerate() {
        let p = points[i];
        if !(p.0.is_finite() && p.1.is_finite()) {
            continue;
        }
        let text = label_of(run);
        let tw = area
            .estimate_text_size(&text, &TextStyle::from((FAMILY, font_size).into_font()))
            .map_or(text.len() as i32 * 8, |(w, _)| w as i32);
        let th = font_size;
        let (px, py) = chart.backend_coord(&p);
        let (px, py) = (px - base.0, py - base.1);
        let candidates = [
            (9, -th / 2),
            (9, -th - 4),
            (9, 4),
            (-tw - 9, -th / 2),
            (-tw - 9, -th - 4),
            (-tw - 9, 4),
            (-tw / 2, -th - 10),
            (-tw / 2, 10),
            (9, -2 * th - 6),
            (9, th + 6),
            (-tw - 9, -2 * th - 6),
            (-tw - 9, th + 6),
        ];
        let fits =
            |r: &Rect| r.x0 >= 0 && r.y0 >= 0 && r.x1 <= area_w as i32 && r.y1 <= area_h as i32;
        let rect_at = |(dx, dy): (i32, i32)| Rect {
            x0: px + dx + base.0,
            y0: py + dy + base.1,
            x1: px + dx + tw + base.0,
            y1: py + dy + th + base.1,
        };
        let chosen = candidates
            .iter()
            .copied()
            .find(|c| {
                let r = rect_at(*c);
                let local = Rect {
                    x0: r.x0 - base.0,
                    y0: r.y0 - base.1,
                    x1: r.x1 - base.0,
                    y1: r.y1 - base.1,
                };
                fits(&local) && !taken.iter().any(|t| t.overlaps(&r))
            })
            .unwrap_or(candidates[0]);
        taken.push(rect_at(chosen));
        let colour = if front[i] { front_colour } else { BLACK };
        area.draw(&Text::new(
            text,
            (px + chosen.0, py + chosen.1),
            (FAMILY, font_size).into_font().color(&colour),
        ))
        .map_err(err)?;
    }
    Ok(())
}
