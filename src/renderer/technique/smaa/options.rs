//! SMAA's public options: the quality preset and what the edge pass
//! detects edges in.

use crate::{Error, Result};
use std::str::FromStr;

/// SMAA's quality presets, with the reference implementation's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SmaaPreset {
    /// Threshold 0.15, 4 search steps, no diagonals, no corner rounding.
    Low,
    /// Threshold 0.1, 8 search steps, no diagonals, no corner rounding.
    Medium,
    /// Threshold 0.1, 16 search steps, 8 diagonal steps, corner rounding 25
    /// (the default).
    #[default]
    High,
    /// Threshold 0.05, 32 search steps, 16 diagonal steps, corner rounding 25.
    Ultra,
}

impl SmaaPreset {
    /// Every preset, by name.
    pub const ALL: [(SmaaPreset, &'static str); 4] = [
        (SmaaPreset::Low, "low"),
        (SmaaPreset::Medium, "medium"),
        (SmaaPreset::High, "high"),
        (SmaaPreset::Ultra, "ultra"),
    ];

    /// Its name (`low`, `medium`, `high`, `ultra`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map_or("high", |(_, n)| n)
    }

    /// The edge threshold: the least change of luma (or of a colour
    /// channel, 0..1 in the sRGB-encoded image) that is an edge.
    pub fn threshold(self) -> f32 {
        match self {
            SmaaPreset::Low => 0.15,
            SmaaPreset::Medium | SmaaPreset::High => 0.1,
            SmaaPreset::Ultra => 0.05,
        }
    }

    /// The walk's steps each way along an edge (two pixels a step).
    pub fn search_steps(self) -> u32 {
        match self {
            SmaaPreset::Low => 4,
            SmaaPreset::Medium => 8,
            SmaaPreset::High => 16,
            SmaaPreset::Ultra => 32,
        }
    }

    /// The cells walked each way along a diagonal run of one-pixel steps
    /// (`None`: diagonal runs are weighed as their orthogonal pieces).
    pub fn diagonal_steps(self) -> Option<u32> {
        match self {
            SmaaPreset::Low | SmaaPreset::Medium => None,
            SmaaPreset::High => Some(8),
            SmaaPreset::Ultra => Some(16),
        }
    }

    /// Corner rounding in percent: how much of the smoothing a sharp
    /// corner keeps (`None`: corners are not told apart from steps, and are
    /// smoothed fully).
    pub fn corner_rounding(self) -> Option<u32> {
        match self {
            SmaaPreset::Low | SmaaPreset::Medium => None,
            SmaaPreset::High | SmaaPreset::Ultra => Some(25),
        }
    }
}

/// What the edge pass compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SmaaEdges {
    /// The luma of the sRGB-encoded image (the default).
    #[default]
    Luma,
    /// Each colour channel: an edge where any one changes enough.
    Color,
    /// The view distance from the G-buffer's (resolved) depth: an edge
    /// where it jumps by more than the threshold relative to the nearer of
    /// the two (0.1: a tenth). Geometry edges only; no local contrast
    /// adaptation.
    Depth,
}

impl SmaaEdges {
    /// Every mode, by name.
    pub const ALL: [(SmaaEdges, &'static str); 3] = [
        (SmaaEdges::Luma, "luma"),
        (SmaaEdges::Color, "color"),
        (SmaaEdges::Depth, "depth"),
    ];

    /// Its name (`luma`, `color`, `depth`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(e, _)| *e == self)
            .map_or("luma", |(_, n)| n)
    }
}

/// SMAA's options: the preset and what the edge pass compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SmaaOptions {
    /// Threshold, search steps and corner rounding.
    pub preset: SmaaPreset,
    /// Luma, colour or depth edges.
    pub edges: SmaaEdges,
}

impl SmaaOptions {
    /// What [`SmaaOptions::from_str`] accepts, for error messages.
    pub const HELP: &'static str = "smaa options: preset=low|medium|high|ultra (default high), edges=luma|color|depth (default luma)";

    /// Parse options written `preset=P`, `edges=E` (the parts after the
    /// colons of `smaa:preset=ultra:edges=color`); `spec` names the whole
    /// entry in the one-line error.
    pub fn parse_options(options: &[&str], spec: &str) -> Result<SmaaOptions> {
        let mut out = SmaaOptions::default();
        for option in options {
            let bad = |what: &str| {
                Error::invalid(format!(
                    "`{spec}`: {what} `{option}`; {}",
                    SmaaOptions::HELP
                ))
            };
            let (key, value) = option
                .split_once('=')
                .ok_or_else(|| bad("unknown option"))?;
            match key {
                "preset" => {
                    out.preset = SmaaPreset::ALL
                        .iter()
                        .find(|(_, n)| *n == value)
                        .map(|(p, _)| *p)
                        .ok_or_else(|| bad("unknown preset in"))?;
                }
                "edges" => {
                    out.edges = SmaaEdges::ALL
                        .iter()
                        .find(|(_, n)| *n == value)
                        .map(|(e, _)| *e)
                        .ok_or_else(|| bad("unknown edge mode in"))?;
                }
                _ => return Err(bad("unknown option")),
            }
        }
        Ok(out)
    }
}

impl FromStr for SmaaOptions {
    type Err = Error;

    /// `preset=P:edges=E` (either, both or neither; empty: the defaults).
    fn from_str(s: &str) -> Result<Self> {
        let options: Vec<&str> = s.split(':').filter(|o| !o.is_empty()).collect();
        SmaaOptions::parse_options(&options, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_parse_and_refuse_in_one_line() {
        assert_eq!("".parse::<SmaaOptions>().unwrap(), SmaaOptions::default());
        let o: SmaaOptions = "preset=ultra:edges=color".parse().unwrap();
        assert_eq!((o.preset, o.edges), (SmaaPreset::Ultra, SmaaEdges::Color));
        assert_eq!(SmaaOptions::default().preset, SmaaPreset::High);
        for bad in ["preset=extreme", "edges=normal", "steps=3", "preset"] {
            let e = bad.parse::<SmaaOptions>().unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(
                e.contains(bad) && e.contains("preset=low|medium|high|ultra"),
                "{e}"
            );
        }
        let values: Vec<_> = SmaaPreset::ALL
            .iter()
            .map(|(p, _)| {
                (
                    p.threshold(),
                    p.search_steps(),
                    p.diagonal_steps(),
                    p.corner_rounding(),
                )
            })
            .collect();
        assert_eq!(
            values,
            [
                (0.15, 4, None, None),
                (0.1, 8, None, None),
                (0.1, 16, Some(8), Some(25)),
                (0.05, 32, Some(16), Some(25))
            ]
        );
    }
}
