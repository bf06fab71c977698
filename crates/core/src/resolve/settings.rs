//! The resolve's parameters, shared by the GLSL pass and the CPU reference.

use std::fmt;
use std::str::FromStr;

/// How the reference sample of a pixel is chosen, and whether samples are
/// weighted by closeness to it (docs/resolve.md, "The math").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum ResolveMethod {
    /// Every sample weighs 1: what a hardware resolve (`glBlitFramebuffer`) does.
    /// Its reference sample (for `Select` attachments and depth) is the median's.
    Average,
    /// Reference = nearest sample.
    Front,
    /// Reference = the median sample by (depth, index), a tie unbiased: for
    /// an even N the lower of the two middle samples (rank N/2 − 1) on
    /// pixels whose window coordinates `x + y` are even, the upper (rank
    /// N/2) on the others; rank ⌊N/2⌋ for an odd N. Half-covered silhouette
    /// pixels then go to the nearer and the farther surface alike, so a
    /// thin object is drawn as wide as it is (docs/resolve.md, "The math").
    Median,
    /// Reference = farthest sample.
    Back,
    /// Reference = the sample at rank ⌊N/2⌋ by (depth, index) on every
    /// pixel: FreeSpace Open's median, which for an even N always takes the
    /// farther middle sample, so half-covered silhouette pixels go to what
    /// lies behind (docs/freespace-open.md).
    UpperMedian,
}

/// The closeness window of the depth-aware methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
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
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// Read the terms off a column-major projection matrix (`m[10]` and
    /// `m[14]`, as `glUniformMatrix4fv` takes it untransposed).
    pub fn from_matrix(m: &[f64; 16], zero_to_one: bool, clear_depth: f64) -> Self {
        DepthProjection {
            p22: m[10],
            p23: m[14],
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
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// Opt-in, with the fast path: also take sample 0 where every sample is
    /// geometry, the depth samples lie on one plane (within rounding) over
    /// the standard sample pattern, and the first blended attachment's
    /// samples are all equal (default off). For hosts whose key is the depth
    /// buffer (`KeySource::Depth`): one triangle's samples have different
    /// depths, so the exact test (equal keys) fails on nearly every pixel it
    /// covers. Not exact: such a pixel is taken to be one fragment, and
    /// its depth is sample 0's (see `cpu::plane_fits`).
    #[cfg_attr(feature = "serde", serde(default))]
    pub plane_uniformity: bool,
    /// Opt-in, with the fast path and a position key: a pixel is uniform
    /// when the position attachment's samples are all equal (as floats
    /// compare), and its depth samples after the first are not read
    /// (default off). The exact test also reads every depth sample, for
    /// each sample's background test. Not exact where a geometry sample's
    /// position equals a background sample's (an attachment cleared to a
    /// value geometry writes), or where one fragment's depth samples
    /// straddle the clear depth; such a pixel takes sample 0. No effect with
    /// a depth key; takes precedence over `plane_uniformity`.
    #[cfg_attr(feature = "serde", serde(default))]
    pub position_uniformity: bool,
    /// Selective anti-aliasing: which pixels are resolved at all; the others
    /// take one sample, as a uniform pixel does (default: every pixel).
    pub selection: Selection,
    /// Resolved layers per pixel: 1 (the default) is the resolve of
    /// docs/resolve.md's "The math"; 2 also resolves the largest cluster of samples
    /// outside the reference's into a second G-buffer with its coverage
    /// (the README's "second layer"), and splits clusters by normal as well
    /// as by depth where a normal attachment is named.
    #[cfg_attr(feature = "serde", serde(default = "one_layer"))]
    pub layers: u32,
    /// With a normal attachment (one layer or two): two geometry samples
    /// close in depth are one surface only when the cosine between their
    /// normals is at least this (default 0.95).
    #[cfg_attr(feature = "serde", serde(default = "default_normal_threshold"))]
    pub normal_threshold: f64,
}

#[cfg(feature = "serde")]
fn one_layer() -> u32 {
    1
}

#[cfg(feature = "serde")]
fn default_normal_threshold() -> f64 {
    DEFAULT_NORMAL_THRESHOLD
}

/// [`ResolveSettings::normal_threshold`]'s default: the cosine of about 18°.
pub const DEFAULT_NORMAL_THRESHOLD: f64 = 0.95;

/// Selective anti-aliasing: outside the selection a pixel takes one
/// sample — sample 0 of every attachment and of depth, exactly as a uniform
/// pixel on the fast path does. The criteria combine: a pixel is resolved
/// only when it passes every one that is set.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Selection {
    /// Resolve only pixels whose centre lies in this screen region (a VR
    /// lens's sweet spot, a HUD-free area).
    pub region: Option<Region>,
    /// Resolve only pixels with a geometry sample at most this far away
    /// (the depth key's units: view-space distance).
    pub max_depth: Option<f64>,
    /// Resolve only pixels where some sample of this attachment component is
    /// at least 0.5: a per-object flag the host's model shader writes (the
    /// demo renderer writes the object's `antialias` flag into `color.a`).
    pub flag: Option<SelectionFlag>,
}

/// A screen region, in pixels with the origin at the top-left corner (as
/// images are read); pixel `(x, y)` is inside when its centre is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case", tag = "shape"))]
pub enum Region {
    /// `x <= cx < x + width`, `y <= cy < y + height` for the pixel centre `(cx, cy)`.
    Rect {
        /// Left edge.
        x: f64,
        /// Top edge.
        y: f64,
        /// Width.
        width: f64,
        /// Height.
        height: f64,
    },
    /// `((cx − x) / rx)² + ((cy − y) / ry)² <= 1`.
    Ellipse {
        /// Centre, x.
        x: f64,
        /// Centre, y (from the top).
        y: f64,
        /// Horizontal radius.
        rx: f64,
        /// Vertical radius.
        ry: f64,
    },
}

/// The attachment component that carries a per-object anti-aliasing flag.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SelectionFlag {
    /// The colour attachment holding the flag (a float or normalised format).
    pub attachment: crate::gl::ColorAttachment,
    /// Component, 0..=3 (x, y, z, w).
    pub component: u8,
}

impl Selection {
    /// Whether any criterion is set.
    pub fn is_active(&self) -> bool {
        self.region.is_some() || self.max_depth.is_some() || self.flag.is_some()
    }

    fn validate(&self) -> crate::Result<()> {
        if let Some(d) = self.max_depth.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(crate::Error::invalid(format!(
                "the selective-AA depth threshold must be a finite distance above 0, got {d}"
            )));
        }
        if let Some(f) = self.flag.filter(|f| f.component > 3) {
            return Err(crate::Error::invalid(format!(
                "the selective-AA flag component must be 0..=3 (x, y, z, w), got {}",
                f.component
            )));
        }
        match &self.region {
            Some(region) => region.validate(),
            None => Ok(()),
        }
    }
}

impl FromStr for Region {
    type Err = crate::Error;

    /// `rect:X,Y,W,H` or `ellipse:CX,CY,RX,RY`, in pixels from the top-left corner.
    fn from_str(s: &str) -> crate::Result<Self> {
        let bad = |why: &str| {
            crate::Error::invalid(format!(
                "region `{s}`: {why}; expected rect:X,Y,W,H or ellipse:CX,CY,RX,RY (pixels, origin top-left)"
            ))
        };
        let (shape, numbers) = s.split_once(':').ok_or_else(|| bad("no shape"))?;
        let v: Vec<f64> = numbers
            .split(',')
            .map(|n| n.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad("not four numbers"))?;
        let [a, b, c, d] = v[..] else {
            return Err(bad("not four numbers"));
        };
        let region = match shape {
            "rect" => Region::Rect {
                x: a,
                y: b,
                width: c,
                height: d,
            },
            "ellipse" => Region::Ellipse {
                x: a,
                y: b,
                rx: c,
                ry: d,
            },
            _ => return Err(bad("unknown shape")),
        };
        region.validate().map_err(|e| match e {
            crate::Error::InvalidArgument(why) => bad(&why),
            other => other,
        })?;
        Ok(region)
    }
}

impl Region {
    /// Check that the numbers are finite and the size or radii positive.
    pub fn validate(&self) -> crate::Result<()> {
        match *self {
            Region::Rect {
                x,
                y,
                width,
                height,
            } if !([x, y, width, height].iter().all(|v| v.is_finite())
                && width >= 0.0
                && height >= 0.0) =>
            {
                Err(crate::Error::invalid(format!(
                    "a selective-AA rectangle needs finite numbers and a size of at least 0, got {x},{y} {width}x{height}"
                )))
            }
            Region::Ellipse { x, y, rx, ry }
                if !([x, y, rx, ry].iter().all(|v| v.is_finite()) && rx > 0.0 && ry > 0.0) =>
            {
                Err(crate::Error::invalid(format!(
                    "a selective-AA ellipse needs a finite centre and radii above 0, got ({x},{y}) radii {rx},{ry}"
                )))
            }
            _ => Ok(()),
        }
    }

    /// Whether pixel (`x`, `y`) (row 0 at the top) of an image `height`
    /// pixels high is inside: the very test the shaders make.
    pub fn contains_pixel(&self, x: u32, y: u32, height: u32) -> bool {
        let u = self.window_uniform(height);
        let (cx, cy) = (f64::from(x) + 0.5, f64::from(height) - f64::from(y) - 0.5);
        !self.outside_window(u, cx, cy)
    }

    /// The shader's `u_region` for a target `height_px` tall, in window
    /// coordinates (origin bottom-left): a rectangle as `(x0, y0, x1, y1)`
    /// (inside: `x0 <= c < x1`), an ellipse as `(cx, cy, 1/rx, 1/ry)`.
    /// The CPU reference uses the same numbers.
    pub fn window_uniform(&self, height_px: u32) -> [f64; 4] {
        let h = height_px as f64;
        match *self {
            Region::Rect {
                x,
                y,
                width,
                height,
            } => [x, h - (y + height), x + width, h - y],
            Region::Ellipse { x, y, rx, ry } => [x, h - y, 1.0 / rx, 1.0 / ry],
        }
    }

    /// Whether the pixel whose window-coordinate centre is `(cx, cy)` (origin
    /// bottom-left) is outside, for [`Region::window_uniform`]'s numbers `u`.
    pub fn outside_window(&self, u: [f64; 4], cx: f64, cy: f64) -> bool {
        match self {
            Region::Rect { .. } => cx < u[0] || cy < u[1] || cx >= u[2] || cy >= u[3],
            Region::Ellipse { .. } => {
                let (dx, dy) = ((cx - u[0]) * u[2], (cy - u[1]) * u[3]);
                dx * dx + dy * dy > 1.0
            }
        }
    }
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
            plane_uniformity: false,
            position_uniformity: false,
            selection: Selection::default(),
            layers: 1,
            normal_threshold: DEFAULT_NORMAL_THRESHOLD,
        }
    }
}

impl ResolveSettings {
    /// Check the numeric options; the message says what is accepted.
    pub fn validate(&self) -> crate::Result<()> {
        if !(self.c.is_finite() && self.c > 0.0) {
            return Err(crate::Error::invalid(format!(
                "the window width c must be a finite number above 0, got {}",
                self.c
            )));
        }
        if !(self.c_in.is_finite() && self.c_in >= 0.0 && self.c_in < self.c) {
            return Err(crate::Error::invalid(format!(
                "the inner window width c_in must be at least 0 and below c ({}), got {}",
                self.c, self.c_in
            )));
        }
        if !(1..=2).contains(&self.layers) {
            return Err(crate::Error::invalid(format!(
                "layers must be 1 or 2, got {}",
                self.layers
            )));
        }
        if !(self.normal_threshold.is_finite() && (-1.0..=1.0).contains(&self.normal_threshold)) {
            return Err(crate::Error::invalid(format!(
                "the normal threshold is a cosine, from -1 to 1, got {}",
                self.normal_threshold
            )));
        }
        self.selection.validate()
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
    ResolveMethod::UpperMedian => "upper-median",
);

name_table!(Window, "window",
    Window::Hard => "hard",
    Window::Smooth => "smooth",
);

/// The rule by which one attachment's samples become one value (docs/resolve.md, "The math").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
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

impl ResolveRule {
    /// The rule an attachment of `format` resolves by unless told otherwise:
    /// integer formats are never blended.
    pub const fn default_for(format: crate::gl::Format) -> ResolveRule {
        match format.sample_kind() {
            crate::gl::format::SampleKind::Float => ResolveRule::Blend,
            _ => ResolveRule::Select,
        }
    }
}

name_table!(ResolveRule, "resolve rule",
    ResolveRule::Blend => "blend",
    ResolveRule::BlendNormal => "blend-normal",
    ResolveRule::BlendHdr => "blend-hdr",
    ResolveRule::Select => "select",
);

/// How a host's normal attachment stores a unit normal: what the second
/// layer's normal test decodes before comparing two samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum NormalEncoding {
    /// xyz as they are (a float or snorm attachment).
    #[default]
    Xyz,
    /// xyz packed into `[0, 1]` as `n * 0.5 + 0.5` (an RGBA8 attachment).
    Unorm,
    /// Octahedral: x and y in `[-1, 1]` (Cigolle et al. 2014's mapping).
    Octahedral,
    /// Octahedral packed into `[0, 1]`.
    OctahedralUnorm,
}

impl NormalEncoding {
    /// The unit-length-or-not normal a stored value decodes to (the CPU
    /// mirror of `resolve.frag`'s `decode_normal`).
    pub fn decode(self, v: [f64; 4]) -> [f64; 3] {
        let unpack = |c: f64| c * 2.0 - 1.0;
        match self {
            NormalEncoding::Xyz => [v[0], v[1], v[2]],
            NormalEncoding::Unorm => [unpack(v[0]), unpack(v[1]), unpack(v[2])],
            NormalEncoding::Octahedral | NormalEncoding::OctahedralUnorm => {
                let (x, y) = if self == NormalEncoding::Octahedral {
                    (v[0], v[1])
                } else {
                    (unpack(v[0]), unpack(v[1]))
                };
                let z = 1.0 - x.abs() - y.abs();
                let sign = |c: f64| if c >= 0.0 { 1.0 } else { -1.0 };
                if z < 0.0 {
                    [(1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y), z]
                } else {
                    [x, y, z]
                }
            }
        }
    }
}

name_table!(NormalEncoding, "normal encoding",
    NormalEncoding::Xyz => "xyz",
    NormalEncoding::Unorm => "unorm",
    NormalEncoding::Octahedral => "octahedral",
    NormalEncoding::OctahedralUnorm => "octahedral-unorm",
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_formats_select() {
        use crate::gl::Format;
        assert_eq!(
            ResolveRule::default_for(Format::Rgba8ui),
            ResolveRule::Select
        );
        assert_eq!(
            ResolveRule::default_for(Format::Rgba16f),
            ResolveRule::Blend
        );
    }

    #[test]
    fn regions_contain_the_pixels_whose_centres_they_cover() {
        let r = Region::Rect {
            x: 2.0,
            y: 1.0,
            width: 3.0,
            height: 2.0,
        };
        let inside: Vec<(u32, u32)> = (0..8)
            .flat_map(|y| (0..8).map(move |x| (x, y)))
            .filter(|&(x, y)| r.contains_pixel(x, y, 8))
            .collect();
        assert_eq!(inside, [(2, 1), (3, 1), (4, 1), (2, 2), (3, 2), (4, 2)]);
        // Rows 1 and 2 from the top of an 8-pixel image are rows 6 and 5
        // from the bottom in window coordinates.
        assert_eq!(r.window_uniform(8), [2.0, 5.0, 5.0, 7.0]);
        let e = Region::Ellipse {
            x: 4.0,
            y: 4.0,
            rx: 2.0,
            ry: 1.0,
        };
        let at = |x, y| e.contains_pixel(x, y, 8);
        assert!(at(3, 3) && at(4, 3) && at(3, 4));
        assert!(!at(3, 5) && !at(1, 3) && !at(6, 4));
    }

    #[test]
    fn regions_parse_and_bad_ones_are_one_line_errors() {
        let r: Region = "rect:1,2,30,40".parse().expect("a rectangle");
        assert_eq!(
            r,
            Region::Rect {
                x: 1.0,
                y: 2.0,
                width: 30.0,
                height: 40.0
            }
        );
        let e: Region = "ellipse:5,6,7,8".parse().expect("an ellipse");
        assert!(matches!(e, Region::Ellipse { rx, .. } if rx == 7.0));
        for bad in [
            "square:1,2,3,4",
            "rect:1,2,3",
            "rect:a,b,c,d",
            "ellipse:1,1,0,1",
            "rect",
        ] {
            let err = bad.parse::<Region>().expect_err(bad).to_string();
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(err.contains(bad), "{err}");
        }
    }
}
