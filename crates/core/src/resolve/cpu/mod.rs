//! The resolve's CPU reference, in `f64`: the same math as
//! `resolve.frag`, sample for sample (and the uniform-pixel and
//! selection tests of `complex.glsl`, which every shader shares).
//! Tests compare the GLSL against it; change both together.

use super::{DepthProjection, NormalEncoding, ResolveMethod, ResolveRule, ResolveSettings, Window};

mod blend;
mod crease;
mod second_layer;
#[cfg(test)]
mod tests;

pub use blend::{blend, blend_hdr, blend_normal};
pub use crease::CpuCamera;

/// Where the depth key of a sample comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CpuKeySource {
    /// `z = −position.z` of this attachment (index into the pixel's attachments).
    Position(usize),
    /// `z = −(view_row · (position, 1))` of this attachment: a world-space
    /// position and the view matrix's third row.
    WorldPosition {
        /// Index into the pixel's attachments.
        attachment: usize,
        /// `(m[2], m[6], m[10], m[14])` of the column-major view matrix.
        view_row: [f64; 4],
    },
    /// The depth-buffer value, linearised with the projection.
    Depth(DepthProjection),
}

/// The fixed inputs of a CPU resolve.
#[derive(Clone, Debug)]
pub struct CpuResolve {
    /// Method, window, widths, fast path, depth blending.
    pub settings: ResolveSettings,
    /// One rule per colour attachment.
    pub rules: Vec<ResolveRule>,
    /// Where the key comes from.
    pub key_source: CpuKeySource,
    /// The background's depth-buffer value.
    pub clear_depth: f64,
    /// `tan(fov_y / height_px)`: the view-space size of a pixel at distance 1.
    pub footprint: f64,
    /// The normal attachment (index into the pixel's attachments) and its
    /// encoding: clusters split by normal too (one layer or two).
    pub normal: Option<(usize, NormalEncoding)>,
    /// The camera, for the crease rule that settles a tie between two faces
    /// of a crease (with a normal attachment).
    pub camera: CpuCamera,
}

/// One pixel's samples: `depth[i]` and `attachments[k][i]`.
#[derive(Clone, Debug, Default)]
pub struct PixelSamples {
    /// Depth-buffer value per sample.
    pub depth: Vec<f64>,
    /// Per colour attachment, one RGBA value per sample.
    pub attachments: Vec<Vec<[f64; 4]>>,
}

/// Where a pixel is, for a selective-AA region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelPlace {
    /// Column, from the left.
    pub x: u32,
    /// Row, from the top (as images are read back).
    pub y: u32,
    /// The target's width in pixels.
    pub width: u32,
    /// The target's height in pixels.
    pub height: u32,
}

/// One resolved pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedPixel {
    /// Per colour attachment, the resolved value.
    pub attachments: Vec<[f64; 4]>,
    /// The resolved depth-buffer value.
    pub depth: f64,
    /// The reference sample (0 on the fast path).
    pub reference: usize,
    /// Weights per sample (all 1 on the fast path: sample 0 stands for them all).
    pub weights: Vec<f64>,
    /// The pixel took the slow path.
    pub complex: bool,
    /// A sample sits so close to a window edge or a depth tie that `f32`
    /// arithmetic may decide it differently: compare such pixels loosely.
    pub ambiguous: bool,
}

/// The second resolved layer of one pixel ([`ResolveSettings::layers`] = 2).
#[derive(Clone, Debug, PartialEq)]
pub struct SecondLayerPixel {
    /// Per colour attachment, the second cluster's resolved value (zeros
    /// where there is no second cluster).
    pub attachments: Vec<[f64; 4]>,
    /// The second cluster's depth-buffer value; the clear depth where there
    /// is none.
    pub depth: f64,
    /// The second cluster's seed (its reference sample), if there is one.
    pub reference: Option<usize>,
    /// Weights per sample (0 outside the second cluster).
    pub weights: Vec<f64>,
    /// The second layer's share of the pixel, `(n2 + j2) / N`: its
    /// cluster's samples and the samples of no kept cluster that join it
    /// (0 without a second cluster).
    pub coverage: f64,
    /// Samples in neither kept cluster (a pixel of three surfaces or more),
    /// counted by the layer each joins: `[j1, j2]`.
    pub joined: [usize; 2],
    /// `f32` may decide a membership differently: compare loosely.
    pub ambiguous: bool,
}

/// Per-sample classification shared by the steps below.
struct Keys {
    z: Vec<f64>,
    bg: Vec<bool>,
}

impl Keys {
    /// Strict order by (z, index) with background at +infinity.
    fn less(&self, i: usize, j: usize) -> bool {
        if self.bg[i] != self.bg[j] {
            return self.bg[j];
        }
        if !self.bg[i] && self.z[i] != self.z[j] {
            return self.z[i] < self.z[j];
        }
        i < j
    }
}

/// The standard sample pattern for `n` samples (2, 4, 8 or 16): offsets
/// from the pixel centre in sixteenths of a pixel, x right and y up as GL
/// reports them (llvmpipe's 4x pattern; most GPUs use these for 2x to 16x).
/// `resolve.frag`'s `SAMPLE_POS` holds the same numbers.
pub fn standard_sample_positions(n: usize) -> Option<&'static [[f64; 2]]> {
    const P2: [[f64; 2]; 2] = [[4.0, 4.0], [-4.0, -4.0]];
    const P4: [[f64; 2]; 4] = [[-2.0, -6.0], [6.0, -2.0], [-6.0, 2.0], [2.0, 6.0]];
    const P8: [[f64; 2]; 8] = [
        [1.0, -3.0],
        [-1.0, 3.0],
        [5.0, 1.0],
        [-3.0, -5.0],
        [-5.0, 5.0],
        [-7.0, -1.0],
        [3.0, 7.0],
        [7.0, -7.0],
    ];
    const P16: [[f64; 2]; 16] = [
        [1.0, 1.0],
        [-1.0, -3.0],
        [-3.0, 2.0],
        [4.0, -1.0],
        [-5.0, -2.0],
        [2.0, 5.0],
        [5.0, 3.0],
        [3.0, -5.0],
        [-2.0, 6.0],
        [0.0, -7.0],
        [-4.0, -6.0],
        [-6.0, 4.0],
        [-8.0, 0.0],
        [7.0, -4.0],
        [6.0, 7.0],
        [-7.0, -8.0],
    ];
    match n {
        2 => Some(&P2),
        4 => Some(&P4),
        8 => Some(&P8),
        16 => Some(&P16),
        _ => None,
    }
}

/// Whether depth-buffer values `depth[i]` lie on one plane over the standard
/// sample pattern, within `2^-22·max|d| + 2^-23` (a few roundings of the
/// rasteriser's interpolation, or of a 24-bit buffer), and whether `f32`
/// may decide that differently (the largest residual at the tolerance).
/// Up to 3 samples always fit. A count without a standard pattern never
/// fits. `resolve.frag`'s `plane_fits` is the same computation in `f32`.
///
/// The fit is least squares over `e_i = d_i − d_0` (small and exact where
/// the depths are close): with positions and `e` centred on their means,
/// the slopes solve the 2x2 normal equations, and the residuals are what
/// the plane leaves.
pub fn plane_fits(depth: &[f64]) -> (bool, bool) {
    let n = depth.len();
    if n <= 3 {
        return (true, false);
    }
    let Some(pos) = standard_sample_positions(n) else {
        return (false, false);
    };
    let nf = n as f64;
    let (mx, my) = (
        pos.iter().map(|p| p[0]).sum::<f64>() / nf,
        pos.iter().map(|p| p[1]).sum::<f64>() / nf,
    );
    let e: Vec<f64> = depth.iter().map(|d| d - depth[0]).collect();
    let me = e.iter().sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy, mut sxe, mut sye) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let (x, y, v) = (pos[i][0] - mx, pos[i][1] - my, e[i] - me);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxe += x * v;
        sye += y * v;
    }
    let det = sxx * syy - sxy * sxy;
    let b = (syy * sxe - sxy * sye) / det;
    let c = (sxx * sye - sxy * sxe) / det;
    let mut worst: f64 = 0.0;
    let mut spread: f64 = 0.0;
    for i in 0..n {
        let residual = (e[i] - me) - b * (pos[i][0] - mx) - c * (pos[i][1] - my);
        worst = worst.max(residual.abs());
        spread = spread.max(e[i].abs());
    }
    let largest = depth.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let tolerance = largest * 2f64.powi(-22) + 2f64.powi(-23);
    if !worst.is_finite() {
        return (false, false);
    }
    // f32 rounds the residuals by about 1e-6 of the depths' spread.
    let ambiguous = (worst - tolerance).abs() <= 1e-3 * tolerance + 4e-6 * spread;
    (worst <= tolerance, ambiguous)
}

/// Whether the pixel at `at` has odd parity: its window coordinates (GL's,
/// from the bottom-left, as `gl_FragCoord` has them) sum to an odd number.
/// Without a place the pixel is taken to be at the origin (even). The
/// median's tie and the majority reference's tie go by it.
pub fn odd_pixel(at: Option<PixelPlace>) -> bool {
    // x + (height − 1 − y) has the parity of x + y + height + 1.
    at.is_some_and(|at| (at.x + at.y + at.height + 1) % 2 == 1)
}

impl CpuResolve {
    /// The opt-in plane test ([`ResolveSettings::plane_uniformity`]): every
    /// sample is geometry, the depths fit one plane ([`plane_fits`]) and the
    /// first blended attachment's samples are all equal (as `f32` compares:
    /// NaN never, −0 and +0 do). The second value: `f32` may decide the
    /// plane differently.
    fn plane_uniform(&self, px: &PixelSamples, keys: &Keys) -> (bool, bool) {
        let Some(k) = self.rules.iter().position(|r| *r != ResolveRule::Select) else {
            return (false, false);
        };
        if keys.bg.iter().any(|&b| b) {
            return (false, false);
        }
        let (fits, ambiguous) = plane_fits(&px.depth);
        let values = &px.attachments[k];
        let equal = values.iter().all(|v| *v == values[0]);
        (fits && equal, ambiguous && equal)
    }

    fn keys(&self, px: &PixelSamples) -> Keys {
        let n = px.depth.len();
        let mut z = Vec::with_capacity(n);
        let mut bg = Vec::with_capacity(n);
        for i in 0..n {
            let depth = px.depth[i];
            let key = match self.key_source {
                CpuKeySource::Position(k) => -px.attachments[k][i][2],
                CpuKeySource::WorldPosition {
                    attachment,
                    view_row: v,
                } => {
                    let p = px.attachments[attachment][i];
                    -(v[0] * p[0] + v[1] * p[1] + v[2] * p[2] + v[3])
                }
                CpuKeySource::Depth(proj) => proj.linearize(depth),
            };
            bg.push(depth == self.clear_depth || !key.is_finite());
            z.push(key);
        }
        Keys { z, bg }
    }

    /// The reference sample for a method at the pixel `at`, ties to the
    /// lower index.
    fn reference(&self, keys: &Keys, at: Option<PixelPlace>) -> usize {
        let n = keys.z.len();
        match self.settings.method {
            ResolveMethod::Front => (1..n).fold(0, |r, i| if keys.less(i, r) { i } else { r }),
            ResolveMethod::Back => (1..n).fold(0, |r, i| {
                let farther = !keys.bg[r] && (keys.bg[i] || keys.z[i] > keys.z[r]);
                if farther { i } else { r }
            }),
            ResolveMethod::Median | ResolveMethod::Average | ResolveMethod::UpperMedian => {
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&a, &b| {
                    if keys.less(a, b) {
                        std::cmp::Ordering::Less
                    } else if keys.less(b, a) {
                        std::cmp::Ordering::Greater
                    } else {
                        std::cmp::Ordering::Equal
                    }
                });
                order[self.median_rank(n, at)]
            }
        }
    }

    /// The rank (0 = nearest) the median's reference takes among the
    /// samples in `order` (sorted by key, nearest first) at the pixel `at`.
    /// [`ResolveMethod::UpperMedian`] and an odd count: ⌊n/2⌋. An even
    /// count has two middle ranks: `n/2 − 1` on pixels of even parity
    /// ([`odd_pixel`]), `n/2` on the others, so that half-covered pixels go
    /// to either surface alike.
    pub(crate) fn median_rank(&self, n: usize, at: Option<PixelPlace>) -> usize {
        if self.settings.method == ResolveMethod::UpperMedian {
            return n / 2;
        }
        (n + usize::from(odd_pixel(at))).saturating_sub(1) / 2
    }

    /// The closeness weight of sample `i` to reference `r`, and whether it is
    /// within `f32` noise of a window edge.
    fn closeness(&self, keys: &Keys, i: usize, r: usize) -> (f64, bool) {
        if i == r || self.settings.method == ResolveMethod::Average {
            return (1.0, false);
        }
        if keys.bg[r] {
            return (if keys.bg[i] { 1.0 } else { 0.0 }, false);
        }
        if keys.bg[i] {
            return (0.0, false);
        }
        let (zi, zr) = (keys.z[i], keys.z[r]);
        let d = (zi - zr).abs();
        // resolve.frag's closeness: a key at or behind the eye has no window.
        let m = zi.min(zr).max(0.0) * self.footprint;
        let (c, c_in) = (self.settings.c, self.settings.c_in);
        // f32 rounds each depth to about 6e-8 of itself and the edge to about 1e-7.
        let near =
            |edge: f64| (d - edge).abs() <= 1e-6 * zi.abs().max(zr.abs()) + 1e-5 * edge.abs();
        match self.settings.window {
            Window::Hard => (if d <= c * m { 1.0 } else { 0.0 }, near(c * m)),
            Window::Smooth => {
                let w = if d <= c_in * m {
                    1.0
                } else if d >= c * m {
                    0.0
                } else {
                    // 1 − smoothstep(t) = smoothstep(1 − t), measured from the outer edge.
                    let u = (c * m - d) / ((c - c_in) * m);
                    u * u * (3.0 - 2.0 * u)
                };
                // The ramp is continuous, but a weight this small is mostly f32
                // rounding on the GPU, and HDR blending can amplify it.
                (w, w > 0.0 && w < 1e-3)
            }
        }
    }

    /// Resolve one pixel. A selective-AA region is not evaluated (it needs
    /// the pixel's place: see [`CpuResolve::resolve_pixel_at`]).
    pub fn resolve_pixel(&self, px: &PixelSamples) -> ResolvedPixel {
        self.resolve_pixel_at(px, None)
    }

    /// Whether a pixel of equal view-space keys is one surface by its
    /// orientation too (the shader's one_orientation), and whether `f32` may
    /// decide it differently: with a normal attachment named, where its depth
    /// samples differ (a half-float position rounds a crease's two facets to
    /// one key), every sample's normal must pass the normal test against
    /// sample 0's. Always one surface for another key or without the test.
    fn one_orientation(&self, px: &PixelSamples, keys: &Keys) -> (bool, bool) {
        if !matches!(self.key_source, CpuKeySource::Position(_))
            || self.splits_by_normal().is_none()
            || px.depth.iter().all(|&d| d == px.depth[0])
        {
            return (true, false);
        }
        let mut ambiguous = false;
        for i in 1..px.depth.len() {
            let (same, near_threshold) = self.same_normal(px, keys, i, 0);
            ambiguous |= near_threshold;
            if !same {
                return (false, ambiguous);
            }
        }
        (true, ambiguous)
    }

    /// Whether the pixel lies outside the selective-AA selection, and whether
    /// `f32` may decide that differently (a key at the depth threshold).
    fn outside_selection(
        &self,
        px: &PixelSamples,
        keys: &Keys,
        at: Option<PixelPlace>,
    ) -> (bool, bool) {
        let sel = &self.settings.selection;
        let mut outside = false;
        let mut ambiguous = false;
        if let (Some(region), Some(at)) = (sel.region, at) {
            let u = region.window_uniform(at.height);
            let (cx, cy) = (at.x as f64 + 0.5, (at.height - 1 - at.y) as f64 + 0.5);
            outside |= region.outside_window(u, cx, cy);
        }
        if let Some(max_depth) = sel.max_depth {
            let geometry = (0..keys.z.len()).filter(|&i| !keys.bg[i]);
            outside |= !geometry.clone().any(|i| keys.z[i] <= max_depth);
            ambiguous |= geometry
                .into_iter()
                .any(|i| (keys.z[i] - max_depth).abs() <= 1e-6 * max_depth.abs());
        }
        if let Some(flag) = sel.flag {
            // The CPU inputs are numbered in order: attachment k is input k.
            let values = &px.attachments[flag.attachment.0 as usize];
            outside |= !values
                .iter()
                .any(|v| v[usize::from(flag.component.min(3))] >= 0.5);
        }
        (outside, ambiguous)
    }

    /// Resolve the pixel at `at` (needed for a selective-AA region).
    pub fn resolve_pixel_at(&self, px: &PixelSamples, at: Option<PixelPlace>) -> ResolvedPixel {
        let n = px.depth.len();
        let keys = self.keys(px);

        // A world-space key compares whole positions (the shader's keys_uniform).
        let same_key = |i: usize| match self.key_source {
            CpuKeySource::WorldPosition { attachment, .. } => {
                let a = &px.attachments[attachment];
                a[i][..3] == a[0][..3] && px.depth[i] == px.depth[0]
            }
            _ => keys.z[i] == keys.z[0],
        };
        let position_test = match self.key_source {
            CpuKeySource::Position(k) | CpuKeySource::WorldPosition { attachment: k, .. }
                if self.settings.fast_path && self.settings.position_uniformity =>
            {
                Some(k)
            }
            _ => None,
        };
        let mut uniform = match position_test {
            // The opt-in test: the key attachment's samples alone (f32 compares).
            Some(k) => px.attachments[k].iter().all(|v| *v == px.attachments[k][0]),
            None => {
                self.settings.fast_path
                    && (1..n).all(|i| keys.bg[i] == keys.bg[0] && (keys.bg[0] || same_key(i)))
            }
        };
        let mut orientation_ambiguous = false;
        if uniform && position_test.is_none() {
            let (one, ambiguous) = self.one_orientation(px, &keys);
            uniform = one;
            orientation_ambiguous = ambiguous;
        }
        let (outside, mut selection_ambiguous) = self.outside_selection(px, &keys, at);
        selection_ambiguous |= orientation_ambiguous;
        if self.settings.fast_path
            && self.settings.plane_uniformity
            && position_test.is_none()
            && !uniform
        {
            let (plane, ambiguous) = self.plane_uniform(px, &keys);
            uniform = plane;
            selection_ambiguous |= ambiguous;
        }
        if uniform || outside {
            return ResolvedPixel {
                attachments: px.attachments.iter().map(|a| a[0]).collect(),
                depth: px.depth[0],
                reference: 0,
                weights: vec![1.0; n],
                complex: false,
                ambiguous: selection_ambiguous,
            };
        }

        let (r, mut ambiguous) = self.majority_reference(px, &keys, self.reference(&keys, at), at);
        ambiguous |= selection_ambiguous;
        let mut weights = Vec::with_capacity(n);
        for i in 0..n {
            let (w, near_edge) = self.closeness(&keys, i, r);
            // With a normal attachment a sample of another orientation is another surface.
            let (same, near_threshold) = self.same_normal(px, &keys, i, r);
            weights.push(if same { w } else { 0.0 });
            ambiguous |= near_edge || (w > 0.0 && near_threshold);
        }
        // Depths that differ by an f32 rounding may order differently on the GPU.
        for i in 0..n {
            for j in 0..i {
                if !keys.bg[i] && !keys.bg[j] && keys.z[i] != keys.z[j] {
                    let scale = keys.z[i].abs().max(keys.z[j].abs());
                    if (keys.z[i] - keys.z[j]).abs() <= 1e-6 * scale {
                        ambiguous = true;
                    }
                }
            }
        }

        let attachments = px
            .attachments
            .iter()
            .zip(&self.rules)
            .map(|(values, rule)| match rule {
                ResolveRule::Select => values[r],
                ResolveRule::Blend => blend(values, &weights, r),
                ResolveRule::BlendNormal => blend_normal(values, &weights, r),
                ResolveRule::BlendHdr => blend_hdr(values, &weights, r),
            })
            .collect();

        let depth = if self.settings.blend_depth {
            let sum: f64 = (0..n).map(|i| weights[i] * px.depth[i]).sum();
            sum / weights.iter().sum::<f64>()
        } else {
            px.depth[r]
        };

        ResolvedPixel {
            attachments,
            depth,
            reference: r,
            weights,
            complex: true,
            ambiguous,
        }
    }
}
