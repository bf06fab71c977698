//! The resolve's parameters, shared by the GLSL pass and the CPU reference.

use std::fmt;
use std::str::FromStr;

/// How the reference sample of a pixel is chosen, and whether samples are
/// weighted by closeness to it (DESIGN.md section 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ResolveMethod {
    /// Every sample weighs 1: what a hardware resolve (`glBlitFramebuffer`) does.
    /// Its reference sample (for `Select` attachments and depth) is the median's.
    Average,
    /// Reference = nearest sample.
    Front,
    /// Reference = the sample at position ⌊N/2⌋ when sorted by (depth, index).
    Median,
    /// Reference = farthest sample.
    Back,
}

/// The closeness window of the depth-aware methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Window {
    /// `w = 1` if `d <= c·m`, else 0 (the paper's Eq. 1).
    Hard,
    /// `w = 1 − smoothstep(c_in·m, c·m, d)`.
    Smooth,
}

/// How the depth-buffer value maps back to a positive view distance.
///
/// A GL projection matrix gives `z_clip = p22·z_view + p23` and
/// `w_clip = −z_view`, so with `Z = −z_view` the distance is
/// `Z = p23 / (z_ndc + p22)`. That one formula covers standard, reversed-Z and
/// infinite-far projections alike; only `z_ndc`'s relation to the stored depth
/// differs with `glClipControl`'s depth mode.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DepthProjection {
    /// The projection matrix's third-row, third-column entry.
    pub p22: f64,
    /// The projection matrix's third-row, fourth-column entry.
    pub p23: f64,
    /// `true` when depth is stored as `z_ndc` directly (`GL_ZERO_TO_ONE`),
    /// `false` for GL's default `(z_ndc + 1) / 2`.
    pub zero_to_one: bool,
    /// The depth value the background keeps (the clear depth): 1.0, or 0.0 for reversed-Z.
    pub clear_depth: f64,
}

impl DepthProjection {
    /// Read the terms off a column-major projection matrix.
    pub fn from_matrix(m: &glam::DMat4, zero_to_one: bool, clear_depth: f64) -> Self {
        DepthProjection {
            p22: m.z_axis.z,
            p23: m.w_axis.z,
            zero_to_one,
            clear_depth,
        }
    }

    /// Positive view distance of a stored depth value (may be infinite).
    pub fn linearize(&self, depth: f64) -> f64 {
        let z_ndc = if self.zero_to_one {
            depth
        } else {
            2.0 * depth - 1.0
        };
        self.p23 / (z_ndc + self.p22)
    }
}

/// Everything that selects the resolve's behaviour, apart from the layout.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ResolveSettings {
    /// How the reference sample is chosen.
    pub method: ResolveMethod,
    /// Closeness window (ignored by `Average`).
    pub window: Window,
    /// Outer window width in pixel footprints (default 5).
    pub c: f64,
    /// Inner width of the smooth window (default 2.5); must be below `c`.
    pub c_in: f64,
    /// Take the uniform-pixel fast path (default on).
    pub fast_path: bool,
    /// Blend the depth attachment's value instead of selecting the reference's.
    pub blend_depth: bool,
}

impl Default for ResolveSettings {
    fn default() -> Self {
        ResolveSettings {
            method: ResolveMethod::Median,
            window: Window::Smooth,
            c: 5.0,
            c_in: 2.5,
            fast_path: true,
            blend_depth: false,
        }
    }
}

impl ResolveSettings {
    /// Check the numeric options; the message says what is accepted.
    pub fn validate(&self) -> crate::Result<()> {
        if !(self.c.is_finite() && self.c > 0.0) {
            return Err(crate::Error::invalid(format!(
                "--c must be a finite number above 0, got {}",
                self.c
            )));
        }
        if !(self.c_in.is_finite() && self.c_in >= 0.0 && self.c_in < self.c) {
            return Err(crate::Error::invalid(format!(
                "--c-in must be at least 0 and below --c ({}), got {}",
                self.c, self.c_in
            )));
        }
        Ok(())
    }
}

macro_rules! name_table {
    ($ty:ty, $what:literal, $( $variant:path => $name:literal ),+ $(,)?) => {
        impl $ty {
            /// The name used on the command line and in reports.
            pub fn name(self) -> &'static str {
                match self { $( $variant => $name ),+ }
            }
            /// Every value, in declaration order.
            pub fn all() -> &'static [$ty] {
                &[$( $variant ),+]
            }
        }
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
        impl FromStr for $ty {
            type Err = crate::Error;
            fn from_str(s: &str) -> crate::Result<Self> {
                match s {
                    $( $name => Ok($variant), )+
                    _ => Err(crate::Error::invalid(format!(
                        concat!("unknown ", $what, " `{}`; expected one of: {}"),
                        s,
                        [$( $name ),+].join(", ")
                    ))),
                }
            }
        }
    };
}

name_table!(ResolveMethod, "resolve method",
    ResolveMethod::Average => "average",
    ResolveMethod::Front => "front",
    ResolveMethod::Median => "median",
    ResolveMethod::Back => "back",
);

name_table!(Window, "window",
    Window::Hard => "hard",
    Window::Smooth => "smooth",
);

/// The rule by which one attachment's samples become one value (DESIGN.md section 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ResolveRule {
    /// Weighted mean over the samples whose value is finite.
    Blend,
    /// xyz: normalised weighted sum (falls back to the reference's), w: like `Blend`.
    BlendNormal,
    /// Weighted mean in the tonemapped domain `x / (1 + max3(x))`, mapped back.
    BlendHdr,
    /// The reference sample's value, never blended.
    Select,
}

name_table!(ResolveRule, "resolve rule",
    ResolveRule::Blend => "blend",
    ResolveRule::BlendNormal => "blend-normal",
    ResolveRule::BlendHdr => "blend-hdr",
    ResolveRule::Select => "select",
);
