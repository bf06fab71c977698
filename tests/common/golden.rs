//! Golden files for the GL tests (trybuild's discipline, filament's diffs).
//!
//! - A golden is written only when `DEFERRED_MSAA_BLESS=1`; any other value is an error.
//! - A missing golden fails the test and leaves the candidate in
//!   `tests/golden/candidates/` (git-ignored) for a person to look at and bless.
//! - On a mismatch, `NAME-actual.png` and `NAME-difference.png` are written beside
//!   the golden (git-ignored).
//!
//! Per-sample goldens (`NAME.samples.gz`) hold every sample of every
//! attachment and depth as half floats, deflated: a line `blessed on: DRIVER`,
//! one line of JSON naming the planes and their shapes, then the data. Final
//! images are PNGs compared with FLIP; a `tEXt` chunk `blessed on` right after
//! `IHDR` names the driver. DRIVER is `GL_RENDERER | GL_VERSION` of the context
//! that blessed the file (see [`driver`]), so a mismatch after a Mesa upgrade
//! says which Mesa the golden came from. Reading ignores it; files from before
//! it have none and get one when re-blessed.
#![allow(dead_code)]

use deferred_msaa_lab::context::HeadlessContext;
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use image::RgbaImage;
use std::io::{Read, Write};
use std::path::PathBuf;

/// The first line of a per-sample golden, before the driver.
const BLESSED_ON: &str = "blessed on: ";
/// The keyword of a PNG golden's `tEXt` chunk naming the driver.
const PNG_KEYWORD: &str = "blessed on";

fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// Whether this run blesses goldens. Only `1` blesses; any other value is a mistake.
pub fn blessing() -> bool {
    match std::env::var("DEFERRED_MSAA_BLESS") {
        Err(_) => false,
        Ok(v) if v == "1" => true,
        Ok(v) => panic!("DEFERRED_MSAA_BLESS must be unset or exactly `1`, not `{v}`"),
    }
}

/// The driver a golden records as its blesser: `GL_RENDERER | GL_VERSION`, e.g.
/// `llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile) Mesa 22.3.6`.
pub fn driver(ctx: &HeadlessContext) -> String {
    let v = ctx.version();
    format!("{} | {}", v.renderer, v.version_string)
}

/// The driver on one line of printable ASCII, so it fits a header line and a
/// PNG `tEXt` chunk (Latin-1) alike.
fn one_line(driver: &str) -> String {
    driver
        .chars()
        .map(|c| {
            if c.is_ascii() && !c.is_ascii_control() {
                c
            } else {
                ' '
            }
        })
        .collect::<String>()
        .trim()
        .to_string()
}

fn provenance(blessed_on: Option<&str>, driver: &str) -> String {
    format!(
        "golden blessed on: {}; this run: {}",
        blessed_on.unwrap_or("(not recorded)"),
        one_line(driver)
    )
}

fn missing(name: &str, file: &str, write: impl FnOnce(&std::path::Path)) -> ! {
    let dir = golden_dir().join("candidates");
    std::fs::create_dir_all(&dir).expect("creating tests/golden/candidates");
    let path = dir.join(file);
    write(&path);
    panic!(
        "golden `{name}` is missing: the candidate is in {}; look at it, then run with DEFERRED_MSAA_BLESS=1 to bless",
        path.display()
    );
}

/// One named plane of per-sample float data, `shape` = [samples, height, width, channels].
pub struct Plane {
    pub name: String,
    pub shape: [usize; 4],
    pub data: Vec<f32>,
}

/// How closely per-sample data must match.
#[derive(Clone, Copy, Debug)]
pub struct SampleTolerance {
    /// Absolute difference allowed everywhere.
    pub abs: f32,
    /// Plus this fraction of the golden's magnitude.
    pub rel: f32,
    /// Fraction of values allowed to exceed it (rasterisation may move an
    /// edge sample between Mesa releases).
    pub outlier_fraction: f32,
}

/// A per-sample golden's bytes, headed by the driver that blessed it.
pub fn encode(planes: &[Plane], driver: &str) -> Vec<u8> {
    let mut out = format!("{BLESSED_ON}{}\n", one_line(driver)).into_bytes();
    let header: Vec<serde_json::Value> = planes
        .iter()
        .map(|p| serde_json::json!({"name": p.name, "shape": p.shape}))
        .collect();
    out.extend(serde_json::to_vec(&header).expect("header"));
    out.push(b'\n');
    let mut enc = DeflateEncoder::new(Vec::new(), Compression::best());
    for p in planes {
        for v in &p.data {
            enc.write_all(&half::f16::from_f32(*v).to_le_bytes())
                .expect("deflate");
        }
    }
    out.extend(enc.finish().expect("deflate"));
    out
}

/// The driver that blessed a per-sample golden (`None` for files from before
/// the header) and its planes.
pub fn decode(bytes: &[u8]) -> (Option<String>, Vec<Plane>) {
    let (blessed_on, bytes) = match bytes.strip_prefix(BLESSED_ON.as_bytes()) {
        Some(rest) => {
            let end = rest
                .iter()
                .position(|&b| b == b'\n')
                .expect("golden `blessed on` line");
            (
                Some(String::from_utf8_lossy(&rest[..end]).into_owned()),
                &rest[end + 1..],
            )
        }
        None => (None, bytes),
    };
    let split = bytes
        .iter()
        .position(|&b| b == b'\n')
        .expect("golden header line");
    let header: Vec<serde_json::Value> =
        serde_json::from_slice(&bytes[..split]).expect("golden header");
    let mut raw = Vec::new();
    DeflateDecoder::new(&bytes[split + 1..])
        .read_to_end(&mut raw)
        .expect("inflate");
    let mut values = raw
        .chunks_exact(2)
        .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32());
    let planes = header
        .iter()
        .map(|h| {
            let shape: Vec<usize> = serde_json::from_value(h["shape"].clone()).expect("shape");
            let shape = [shape[0], shape[1], shape[2], shape[3]];
            let n: usize = shape.iter().product();
            Plane {
                name: h["name"].as_str().unwrap_or("").to_string(),
                shape,
                data: values.by_ref().take(n).collect(),
            }
        })
        .collect();
    (blessed_on, planes)
}

/// A PNG golden's bytes: `image` encoded, with a `tEXt` chunk naming the
/// driver inserted right after `IHDR` (where readers meet it first).
pub fn encode_png(image: &RgbaImage, driver: &str) -> Vec<u8> {
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encoding PNG");
    // Signature (8 bytes), then IHDR: length, type, 13 bytes, CRC.
    const IHDR_END: usize = 8 + 4 + 4 + 13 + 4;
    assert_eq!(&png[12..16], b"IHDR", "a PNG starts with IHDR");
    let mut data = format!("{PNG_KEYWORD}\0{}", one_line(driver)).into_bytes();
    let mut crc = flate2::Crc::new();
    crc.update(b"tEXt");
    crc.update(&data);
    let mut chunk = (data.len() as u32).to_be_bytes().to_vec();
    chunk.extend_from_slice(b"tEXt");
    chunk.append(&mut data);
    chunk.extend_from_slice(&crc.sum().to_be_bytes());
    png.splice(IHDR_END..IHDR_END, chunk);
    png
}

/// The driver a PNG golden's `tEXt` chunk names, `None` for files from before it.
pub fn png_blessed_on(png: &[u8]) -> Option<String> {
    let mut at = 8;
    while at + 8 <= png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().ok()?) as usize;
        let kind = &png[at + 4..at + 8];
        let data = png.get(at + 8..at + 8 + len)?;
        if kind == b"IDAT" || kind == b"IEND" {
            return None;
        }
        if kind == b"tEXt"
            && let Some(text) = data.strip_prefix(format!("{PNG_KEYWORD}\0").as_bytes())
        {
            // tEXt is Latin-1; what we write is ASCII.
            return Some(text.iter().map(|&b| b as char).collect());
        }
        at += 12 + len;
    }
    None
}

/// Values are stored as half floats; compare what half precision keeps.
fn quantised(v: f32) -> f32 {
    half::f16::from_f32(v).to_f32()
}

fn same(a: f32, b: f32, tol: SampleTolerance) -> bool {
    if a.is_nan() || b.is_nan() {
        return a.is_nan() && b.is_nan();
    }
    if a.is_infinite() || b.is_infinite() {
        return a == b;
    }
    (a - b).abs() <= tol.abs + tol.rel * b.abs().max(a.abs())
}

/// Compare every sample of every plane with the golden `NAME.samples.gz`;
/// `driver` ([`driver`]) is what a blessed file records and a failure reports.
pub fn check_samples(name: &str, planes: &[Plane], tol: SampleTolerance, driver: &str) {
    let file = format!("{name}.samples.gz");
    let path = golden_dir().join(&file);
    if blessing() {
        std::fs::create_dir_all(golden_dir()).expect("tests/golden");
        std::fs::write(&path, encode(planes, driver)).expect("writing golden");
        eprintln!("blessed {} on {}", path.display(), one_line(driver));
        return;
    }
    let Ok(bytes) = std::fs::read(&path) else {
        missing(name, &file, |p| {
            std::fs::write(p, encode(planes, driver)).expect("writing candidate")
        });
    };
    let (blessed_on, golden) = decode(&bytes);
    let from = provenance(blessed_on.as_deref(), driver);
    assert_eq!(
        golden.len(),
        planes.len(),
        "{name}: the golden has {} planes, the test {} ({from})",
        golden.len(),
        planes.len()
    );
    let mut report = Vec::new();
    let mut worst_plane: Option<(usize, Vec<f32>)> = None;
    for (pi, (g, p)) in golden.iter().zip(planes).enumerate() {
        assert_eq!(
            (g.name.as_str(), g.shape),
            (p.name.as_str(), p.shape),
            "{name}: plane layout changed ({from})"
        );
        let mut bad = 0usize;
        let mut diff = vec![0.0f32; p.shape[1] * p.shape[2]];
        let per_sample = p.shape[1] * p.shape[2] * p.shape[3];
        for (i, (&gv, &pv)) in g.data.iter().zip(&p.data).enumerate() {
            let pv = quantised(pv);
            if !same(pv, gv, tol) {
                bad += 1;
                let pixel = (i % per_sample) / p.shape[3];
                diff[pixel] = diff[pixel].max(if pv.is_finite() && gv.is_finite() {
                    (pv - gv).abs()
                } else {
                    f32::INFINITY
                });
            }
        }
        let allowed = (tol.outlier_fraction * p.data.len() as f32).floor() as usize;
        if bad > allowed {
            report.push(format!(
                "{}: {bad} of {} values differ (allowed {allowed})",
                p.name,
                p.data.len()
            ));
            if worst_plane.is_none() {
                worst_plane = Some((pi, diff));
            }
        }
    }
    if let Some((pi, diff)) = worst_plane {
        let p = &planes[pi];
        let (w, h, c) = (p.shape[2] as u32, p.shape[1] as u32, p.shape[3]);
        let actual = RgbaImage::from_fn(w, h, |x, y| {
            let i = ((y * w + x) as usize) * c;
            let v = |k: usize| {
                (p.data
                    .get(i + k.min(c - 1))
                    .copied()
                    .unwrap_or(0.0)
                    .clamp(0.0, 1.0)
                    * 255.0) as u8
            };
            image::Rgba([v(0), v(1), v(2), 255])
        });
        let difference = RgbaImage::from_fn(w, h, |x, y| {
            let d = diff[(y * w + x) as usize];
            let t = if d.is_finite() {
                (d / (tol.abs + 1e-6)).min(255.0) as u8
            } else {
                255
            };
            image::Rgba([t, 0, if d > 0.0 { 64 } else { 0 }, 255])
        });
        let _ = actual.save(golden_dir().join(format!("{name}-actual.png")));
        let _ = difference.save(golden_dir().join(format!("{name}-difference.png")));
        panic!(
            "{name}: per-sample golden mismatch ({tol:?}):\n  {}\n  images: tests/golden/{name}-actual.png, {name}-difference.png\n  {from}",
            report.join("\n  ")
        );
    }
}

/// FLIP thresholds for a final image.
#[derive(Clone, Copy, Debug)]
pub struct FlipTolerance {
    pub mean: f32,
    pub p99: f32,
}

/// Compare a final image with the golden `NAME.png` by FLIP; `driver` as for
/// [`check_samples`].
pub fn check_image(name: &str, image: &RgbaImage, tol: FlipTolerance, driver: &str) {
    let file = format!("{name}.png");
    let path = golden_dir().join(&file);
    if blessing() {
        std::fs::create_dir_all(golden_dir()).expect("tests/golden");
        std::fs::write(&path, encode_png(image, driver)).expect("writing golden");
        eprintln!("blessed {} on {}", path.display(), one_line(driver));
        return;
    }
    let Ok(bytes) = std::fs::read(&path) else {
        missing(name, &file, |p| {
            std::fs::write(p, encode_png(image, driver)).expect("writing candidate")
        });
    };
    let from = provenance(png_blessed_on(&bytes).as_deref(), driver);
    let golden = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .unwrap_or_else(|e| panic!("{name}: {} does not decode: {e}", path.display()))
        .to_rgba8();
    let stats = deferred_msaa_lab::compare::flip(&golden, image).unwrap_or_else(|| {
        panic!(
            "{name}: size {:?} differs from the golden's {:?} ({from})",
            image.dimensions(),
            golden.dimensions()
        )
    });
    if stats.mean > tol.mean || stats.p99 > tol.p99 {
        let _ = image.save(golden_dir().join(format!("{name}-actual.png")));
        let _ = stats
            .map
            .save(golden_dir().join(format!("{name}-difference.png")));
        panic!(
            "{name}: FLIP mean {:.4} (allowed {}), p99 {:.4} (allowed {}); images: tests/golden/{name}-actual.png, {name}-difference.png; {from}",
            stats.mean, tol.mean, stats.p99, tol.p99
        );
    }
}
