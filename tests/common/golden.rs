//! Golden files for the GL tests (trybuild's discipline, filament's diffs).
//!
//! - A golden is written only when `DEFERRED_MSAA_BLESS=1`; any other value is an error.
//! - A missing golden fails the test and leaves the candidate in
//!   `tests/golden/candidates/` (git-ignored) for a person to look at and bless.
//! - On a mismatch, `NAME-actual.png` and `NAME-difference.png` are written beside
//!   the golden (git-ignored).
//!
//! Per-sample goldens (`NAME.samples.gz`) hold every sample of every
//! attachment and depth as half floats, deflated: one line of JSON naming the
//! planes and their shapes, then the data. Final images are PNGs compared with FLIP.
#![allow(dead_code)]

use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use image::RgbaImage;
use std::io::{Read, Write};
use std::path::PathBuf;

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

fn encode(planes: &[Plane]) -> Vec<u8> {
    let header: Vec<serde_json::Value> = planes
        .iter()
        .map(|p| serde_json::json!({"name": p.name, "shape": p.shape}))
        .collect();
    let mut out = serde_json::to_vec(&header).expect("header");
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

fn decode(bytes: &[u8]) -> Vec<Plane> {
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
    header
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
        .collect()
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

/// Compare every sample of every plane with the golden `NAME.samples.gz`.
pub fn check_samples(name: &str, planes: &[Plane], tol: SampleTolerance) {
    let file = format!("{name}.samples.gz");
    let path = golden_dir().join(&file);
    if blessing() {
        std::fs::create_dir_all(golden_dir()).expect("tests/golden");
        std::fs::write(&path, encode(planes)).expect("writing golden");
        eprintln!("blessed {}", path.display());
        return;
    }
    let Ok(bytes) = std::fs::read(&path) else {
        missing(name, &file, |p| {
            std::fs::write(p, encode(planes)).expect("writing candidate")
        });
    };
    let golden = decode(&bytes);
    assert_eq!(
        golden.len(),
        planes.len(),
        "{name}: the golden has {} planes, the test {}",
        golden.len(),
        planes.len()
    );
    let mut report = Vec::new();
    let mut worst_plane: Option<(usize, Vec<f32>)> = None;
    for (pi, (g, p)) in golden.iter().zip(planes).enumerate() {
        assert_eq!(
            (g.name.as_str(), g.shape),
            (p.name.as_str(), p.shape),
            "{name}: plane layout changed"
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
            "{name}: per-sample golden mismatch ({tol:?}):\n  {}\n  images: tests/golden/{name}-actual.png, {name}-difference.png",
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

/// Compare a final image with the golden `NAME.png` by FLIP.
pub fn check_image(name: &str, image: &RgbaImage, tol: FlipTolerance) {
    let file = format!("{name}.png");
    let path = golden_dir().join(&file);
    if blessing() {
        std::fs::create_dir_all(golden_dir()).expect("tests/golden");
        image.save(&path).expect("writing golden");
        eprintln!("blessed {}", path.display());
        return;
    }
    let Ok(golden) = image::open(&path) else {
        missing(name, &file, |p| image.save(p).expect("writing candidate"));
    };
    let golden = golden.to_rgba8();
    let stats = deferred_msaa_lab::compare::flip(&golden, image).unwrap_or_else(|| {
        panic!(
            "{name}: size {:?} differs from the golden's {:?}",
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
            "{name}: FLIP mean {:.4} (allowed {}), p99 {:.4} (allowed {}); images: tests/golden/{name}-actual.png, {name}-difference.png",
            stats.mean, tol.mean, stats.p99, tol.p99
        );
    }
}
