//! The memory safety valve: what a G-buffer will take, estimated from its
//! layout, size and sample count before anything is allocated, and the
//! sample count stepped down (or the request refused) when that is over a
//! budget. FreeSpace Open let users pick 16x at 4K and fell off a cliff; a
//! budget turns that into a warning and a lower count, or a clear error.
//!
//! The default budget is half of the video memory the driver says is free
//! (`GL_NVX_gpu_memory_info`, `GL_ATI_meminfo`) where it says, else 1 GiB.

use super::GBufferLayout;
use super::bytes::fmt_bytes;
use crate::{Error, Result};
use glow::HasContext;

/// The budget when the driver reports no free memory: 1 GiB.
pub const DEFAULT_BUDGET_BYTES: u64 = 1 << 30;

/// The share of the driver's free video memory a G-buffer may take by default.
pub const DRIVER_FRACTION: f64 = 0.5;

/// `GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX` (KiB).
const NVX_CURRENT_AVAILABLE: u32 = 0x9049;
/// `GL_TEXTURE_FREE_MEMORY_ATI` (four values in KiB, the first the total free).
const ATI_TEXTURE_FREE: u32 = 0x87FC;

/// How many bytes a G-buffer may take, and what to do when it would take more.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MemoryBudget {
    /// The limit in bytes; `None`: [`DRIVER_FRACTION`] of the free video
    /// memory the driver reports, else [`DEFAULT_BUDGET_BYTES`].
    pub bytes: Option<u64>,
    /// Refuse with [`Error::MemoryBudget`] instead of stepping the sample
    /// count down.
    pub strict: bool,
}

impl MemoryBudget {
    /// A budget of `bytes`, stepping down when over it.
    pub fn limit(bytes: u64) -> Self {
        MemoryBudget {
            bytes: Some(bytes),
            strict: false,
        }
    }

    /// The same budget, refusing instead of stepping down.
    pub fn strict(self) -> Self {
        MemoryBudget {
            strict: true,
            ..self
        }
    }

    /// The limit in bytes given what the driver reports, and where it came from.
    pub fn resolve(&self, driver: Option<DriverMemory>) -> (u64, String) {
        match (self.bytes, driver) {
            (Some(b), _) => (b, "given".to_string()),
            (None, Some(d)) => (
                (d.free_bytes as f64 * DRIVER_FRACTION) as u64,
                format!(
                    "{}% of the {} free that {} reports",
                    (DRIVER_FRACTION * 100.0).round(),
                    fmt_bytes(d.free_bytes),
                    d.extension
                ),
            ),
            (None, None) => (
                DEFAULT_BUDGET_BYTES,
                "the default: the driver reports no free memory".to_string(),
            ),
        }
    }
}

/// Free video memory as a driver extension reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct DriverMemory {
    /// `GL_NVX_gpu_memory_info` or `GL_ATI_meminfo`.
    pub extension: &'static str,
    /// Free bytes.
    pub free_bytes: u64,
}

impl DriverMemory {
    /// Ask the current context; `None` where it has neither extension (Mesa's
    /// software rasterisers, most integrated GPUs).
    pub fn query(gl: &glow::Context) -> Option<DriverMemory> {
        let extensions = gl.supported_extensions();
        let kib = if extensions.contains("GL_NVX_gpu_memory_info") {
            let v = unsafe { gl.get_parameter_i32(NVX_CURRENT_AVAILABLE) };
            Some(("GL_NVX_gpu_memory_info", v))
        } else if extensions.contains("GL_ATI_meminfo") {
            let mut v = [0i32; 4];
            unsafe { gl.get_parameter_i32_slice(ATI_TEXTURE_FREE, &mut v) };
            Some(("GL_ATI_meminfo", v[0]))
        } else {
            None
        };
        // A driver that lists an extension but errors on it reports nothing.
        let ok = crate::gl::check_error(gl, "querying free video memory").is_ok();
        kib.filter(|&(_, k)| ok && k > 0)
            .map(|(extension, k)| DriverMemory {
                extension,
                free_bytes: k as u64 * 1024,
            })
    }
}

/// Bytes of a G-buffer of `layout` at `width`×`height`: the single-sample
/// textures every frame resolves into, plus, when multisampling
/// (`twin_samples`), their multisampled twins at that sample count.
pub fn gbuffer_bytes(
    layout: &GBufferLayout,
    width: u32,
    height: u32,
    twin_samples: Option<u32>,
) -> u64 {
    layout.bytes(width, height, 1) + twin_samples.map_or(0, |n| layout.bytes(width, height, n))
}

/// The count a driver really allocates for a request: the smallest offered
/// count at least as large (drivers round up; llvmpipe turns 1–3 into 4),
/// or the request itself when none is (allocating then fails with
/// [`Error::UnsupportedSampleCount`]). `offered` is ascending.
pub fn real_sample_count(requested: u32, offered: &[u32]) -> u32 {
    offered
        .iter()
        .copied()
        .find(|&c| c >= requested)
        .unwrap_or(requested)
}

/// What [`choose_samples`] decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleChoice {
    /// The count to allocate; 1 means single-sample (no multisampled twins).
    pub samples: u32,
    /// Bytes at that count.
    pub bytes: u64,
    /// The count asked for (as the driver would round it) and its bytes,
    /// when that was over the budget and the count was stepped down.
    pub stepped_from: Option<(u32, u64)>,
}

impl SampleChoice {
    /// The warning to show when the count was stepped down, in one line.
    pub fn warning(&self, budget: u64) -> Option<String> {
        let (from, needed) = self.stepped_from?;
        let to = if self.samples > 1 {
            format!(
                "stepping down to {}x ({})",
                self.samples,
                fmt_bytes(self.bytes)
            )
        } else {
            format!(
                "rendering without MSAA ({}{})",
                fmt_bytes(self.bytes),
                if self.bytes > budget {
                    ", still over it"
                } else {
                    ""
                }
            )
        };
        Some(format!(
            "memory budget: the G-buffer needs {} at {from}x, over the budget of {}; {to}",
            fmt_bytes(needed),
            fmt_bytes(budget)
        ))
    }
}

/// Pick the sample count under `budget`, a pure function of the driver's
/// offered counts (ascending) and `bytes_at(count)` (count 1: single-sample).
///
/// `requested` is first rounded as the driver would ([`real_sample_count`]).
/// If it fits it is kept. Otherwise `strict` refuses with
/// [`Error::MemoryBudget`]; else the highest offered lower count that fits
/// is taken, and failing that single-sample (when `allow_single`, even if
/// that is still over: there is nothing lower), or the refusal.
pub fn choose_samples(
    requested: u32,
    offered: &[u32],
    budget: u64,
    strict: bool,
    allow_single: bool,
    bytes_at: impl Fn(u32) -> u64,
) -> Result<SampleChoice> {
    let real = real_sample_count(requested, offered);
    let needed = bytes_at(real);
    if needed <= budget {
        return Ok(SampleChoice {
            samples: real,
            bytes: needed,
            stepped_from: None,
        });
    }
    let refuse = Error::MemoryBudget {
        needed,
        budget,
        samples: real,
    };
    if strict {
        return Err(refuse);
    }
    let lower = offered
        .iter()
        .rev()
        .copied()
        .filter(|&c| c > 1 && c < real)
        .map(|c| (c, bytes_at(c)))
        .find(|&(_, b)| b <= budget);
    match (lower, allow_single) {
        (Some((samples, bytes)), _) => Ok(SampleChoice {
            samples,
            bytes,
            stepped_from: Some((real, needed)),
        }),
        (None, true) => Ok(SampleChoice {
            samples: 1,
            bytes: bytes_at(1),
            stepped_from: Some((real, needed)),
        }),
        (None, false) => Err(refuse),
    }
}

/// The sample count for multisampled twins of textures in `formats` at
/// `width`×`height` under `budget` on the current context (the retrofit's
/// valve: it cannot fall back to single-sample, so when no offered count
/// fits it refuses), and the warning when it stepped down.
pub fn budget_twins(
    gl: &glow::Context,
    formats: &[crate::gl::Format],
    width: u32,
    height: u32,
    requested: u32,
    budget: &MemoryBudget,
) -> Result<(u32, Option<String>)> {
    let mut offered: Option<Vec<u32>> = None;
    for &f in formats {
        let counts = crate::gl::Capabilities::sample_counts_for(gl, f);
        offered = Some(match offered {
            None => counts,
            Some(o) => o.into_iter().filter(|c| counts.contains(c)).collect(),
        });
    }
    let offered = offered.unwrap_or_default();
    let (limit, _) = budget.resolve(DriverMemory::query(gl));
    let texels = u64::from(width) * u64::from(height);
    let per_sample: u64 = formats.iter().map(|f| f.bytes_per_texel() as u64).sum();
    let choice = choose_samples(requested, &offered, limit, budget.strict, false, |n| {
        per_sample * texels * u64::from(n)
    })?;
    let warning = choice.warning(limit);
    if let Some(w) = &warning {
        log::warn!("{w}");
    }
    Ok((choice.samples, warning))
}

/// Parse a byte count: a number with an optional unit, `B`, `K`/`KiB`,
/// `M`/`MiB`, `G`/`GiB` (powers of 1024) or `KB`/`MB`/`GB` (powers of
/// 1000): `512MiB`, `1.5G`, `2000000`.
pub fn parse_bytes(text: &str) -> Result<u64> {
    let s = text.trim();
    let split = s
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(s.len());
    let (number, unit) = s.split_at(split);
    let bad = |why: &str| {
        Error::invalid(format!(
            "`{text}` is not a byte count: {why} (e.g. 512MiB, 1.5GiB, 2000000)"
        ))
    };
    let value: f64 = number.parse().map_err(|_| bad("no number"))?;
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kib" => 1024.0,
        "m" | "mib" => 1024.0 * 1024.0,
        "g" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        _ => return Err(bad("unknown unit")),
    };
    let bytes = value * scale;
    if !bytes.is_finite() || bytes < 1.0 || bytes > u64::MAX as f64 {
        return Err(bad("it must be at least one byte"));
    }
    Ok(bytes.round() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_parse_and_print() {
        assert_eq!(parse_bytes("512MiB").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("2 GB").unwrap(), 2_000_000_000);
        assert_eq!(parse_bytes("4096").unwrap(), 4096);
        for bad in ["", "MiB", "12 parsecs", "0", "-5M", "1e9"] {
            let e = parse_bytes(bad).unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{bad}: {e}");
        }
        assert_eq!(fmt_bytes(512 << 20), "512.0 MiB");
        assert_eq!(fmt_bytes(3 << 29), "1.50 GiB");
        assert_eq!(fmt_bytes(900), "900 B");
    }

    #[test]
    fn the_default_budget_follows_the_driver() {
        let none = MemoryBudget::default();
        assert_eq!(none.resolve(None).0, DEFAULT_BUDGET_BYTES);
        let driver = DriverMemory {
            extension: "GL_NVX_gpu_memory_info",
            free_bytes: 8 << 30,
        };
        let (bytes, source) = none.resolve(Some(driver));
        assert_eq!(bytes, 4 << 30);
        assert!(source.contains("GL_NVX_gpu_memory_info"), "{source}");
        assert_eq!(MemoryBudget::limit(7).resolve(Some(driver)).0, 7);
    }
}
