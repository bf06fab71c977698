//! The resolve's CPU reference, in `f64`: the same math as
//! `resolve.frag`, sample for sample (and the uniform-pixel and
//! selection tests of `complex.glsl`, which every shader shares).
//! Tests compare the GLSL against it; change both together.

use super::{DepthProjection, NormalEncoding, ResolveMethod, ResolveRule, ResolveSettings, Window};

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

fn is_finite4(x: &[f64; 4]) -> bool {
    x.iter().all(|c| c.is_finite())
}

fn max3(x: &[f64; 4]) -> f64 {
    x[0].max(x[1]).max(x[2])
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

    /// The reference sample for a method, ties to the lower index.
    fn reference(&self, keys: &Keys) -> usize {
        let n = keys.z.len();
        match self.settings.method {
            ResolveMethod::Front => (1..n).fold(0, |r, i| if keys.less(i, r) { i } else { r }),
            ResolveMethod::Back => (1..n).fold(0, |r, i| {
                let farther = !keys.bg[r] && (keys.bg[i] || keys.z[i] > keys.z[r]);
                if farther { i } else { r }
            }),
            ResolveMethod::Median | ResolveMethod::Average => {
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
                order[n / 2]
            }
        }
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
        let (outside, mut selection_ambiguous) = self.outside_selection(px, &keys, at);
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

        let (r, mut ambiguous) = self.majority_reference(px, &keys, self.reference(&keys));
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

impl CpuResolve {
    /// Whether clusters split by normal: a normal attachment, with one
    /// layer or two.
    fn splits_by_normal(&self) -> Option<(usize, NormalEncoding)> {
        self.normal
    }

    /// Whether samples `i` and `j` may be one surface by their normals (always,
    /// without the normal test, for background, or for a normal that is not
    /// finite or shorter than 1e-6), and whether `f32` may decide it
    /// differently (a cosine within 1e-5 of the threshold).
    fn same_normal(&self, px: &PixelSamples, keys: &Keys, i: usize, j: usize) -> (bool, bool) {
        let Some((k, encoding)) = self.splits_by_normal() else {
            return (true, false);
        };
        if keys.bg[i] || keys.bg[j] || i == j {
            return (true, false);
        }
        let a = encoding.decode(px.attachments[k][i]);
        let b = encoding.decode(px.attachments[k][j]);
        let length = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let (la, lb) = (length(a), length(b));
        if !(la.is_finite() && lb.is_finite() && la >= 1e-6 && lb >= 1e-6) {
            return (true, false);
        }
        let cos = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
        let t = self.settings.normal_threshold;
        (cos >= t, (cos - t).abs() <= 1e-5)
    }

    /// Whether sample `j`, in neither kept cluster, joins the second layer
    /// (seeded by `s`) rather than the first (whose reference is `r`): the
    /// nearer in depth (background samples are at no distance from each
    /// other and infinitely far from geometry), on a tie the closer in
    /// orientation (the larger cosine, with a normal attachment and
    /// geometry throughout), else the first. The second value: `f32` may
    /// decide differently.
    fn joins_second(
        &self,
        px: &PixelSamples,
        keys: &Keys,
        j: usize,
        r: usize,
        s: usize,
    ) -> (bool, bool) {
        let near_first = keys.bg[j] == keys.bg[r];
        let near_second = keys.bg[j] == keys.bg[s];
        if near_first != near_second {
            return (near_second, false);
        }
        if near_first && !keys.bg[j] {
            let (d1, d2) = ((keys.z[j] - keys.z[r]).abs(), (keys.z[j] - keys.z[s]).abs());
            if d1 != d2 {
                // Close distances may come out in either order in f32, unless
                // the keys are the stored f32 values (a view-space position's
                // z) and f32 subtracts them exactly, as it does keys within a
                // factor of two of each other: then the shader's distances
                // are these.
                let scale = keys.z[j].abs().max(keys.z[r].abs()).max(keys.z[s].abs());
                let exact = |a: f64, b: f64| f64::from(a as f32 - b as f32) == a - b;
                let stored = matches!(self.key_source, CpuKeySource::Position(_))
                    && exact(keys.z[j], keys.z[r])
                    && exact(keys.z[j], keys.z[s]);
                return (d2 < d1, !stored && (d1 - d2).abs() <= 1e-6 * scale);
            }
        }
        let Some((k, encoding)) = self.splits_by_normal() else {
            return (false, false);
        };
        if keys.bg[j] || keys.bg[r] || keys.bg[s] {
            return (false, false);
        }
        let cosine = |a: [f64; 3], b: [f64; 3]| {
            let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let la = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            let lb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            dot / (la * lb)
        };
        let n = |i: usize| encoding.decode(px.attachments[k][i]);
        let (c1, c2) = (cosine(n(j), n(r)), cosine(n(j), n(s)));
        // A NaN (a zero-length normal) compares false: the first.
        (
            c2 > c1,
            (c2 - c1).abs() <= 1e-5 || c1.is_nan() || c2.is_nan(),
        )
    }

    /// With two layers and a normal attachment (any method but `Average`),
    /// the reference `r` moves to the sample within its depth window whose
    /// cluster (the samples within its window and of its orientation) is
    /// the largest, if larger than its own: the first of those in index
    /// order. A crease, or a box's side face just behind its front face, can
    /// put the median on the smaller face; the larger's samples would then
    /// join it and be lit as it. The second value: `f32` may decide
    /// differently.
    fn majority_reference(&self, px: &PixelSamples, keys: &Keys, r: usize) -> (usize, bool) {
        if self.settings.layers != 2
            || self.splits_by_normal().is_none()
            || self.settings.method == ResolveMethod::Average
        {
            return (r, false);
        }
        let n = px.depth.len();
        let mut ambiguous = false;
        let mut size = |s: usize| {
            let mut count = 0;
            for j in 0..n {
                let (inside, unsure) = self.member(px, keys, j, s);
                count += usize::from(inside);
                ambiguous |= unsure;
            }
            count
        };
        let sizes: Vec<usize> = (0..n).map(&mut size).collect();
        let mut best = r;
        for s in 0..n {
            let (w, near_edge) = self.closeness(keys, s, r);
            ambiguous |= near_edge;
            if w > 0.0 && sizes[s] > sizes[best] {
                best = s;
            }
        }
        (best, ambiguous)
    }

    /// Sample `j` belongs to the cluster seeded by `s`: within its window and
    /// of its orientation. The second value: `f32` may decide differently.
    fn member(&self, px: &PixelSamples, keys: &Keys, j: usize, s: usize) -> (bool, bool) {
        let (w, near_edge) = self.closeness(keys, j, s);
        let (same, near_threshold) = self.same_normal(px, keys, j, s);
        (w > 0.0 && same, near_edge || (w > 0.0 && near_threshold))
    }

    /// The second layer of one pixel (see [`SecondLayerPixel`]): of the
    /// samples outside the first layer's cluster (weight 0 there), a seed
    /// outside the first reference's depth window (another surface in depth)
    /// before one inside it (the same depth, another orientation: a crease,
    /// a box's side face), then the largest cluster (each candidate seed's
    /// cluster is the outside samples within its window and of its
    /// orientation), ties to the nearer seed, then the lower index; resolved
    /// by the attachments' rules with the seed as reference. Samples in neither kept cluster join the layer
    /// [`joins_second`](Self::joins_second) says, for the coverage only:
    /// no sample's share of the pixel is lost, and no layer's values blend
    /// surfaces the clusters split. A pixel that takes one sample has none;
    /// without one its attachments are zeros and its depth the clear depth.
    pub fn resolve_second_layer_at(
        &self,
        px: &PixelSamples,
        at: Option<PixelPlace>,
    ) -> SecondLayerPixel {
        let n = px.depth.len();
        let first = self.resolve_pixel_at(px, at);
        let none = |ambiguous| SecondLayerPixel {
            attachments: vec![[0.0; 4]; px.attachments.len()],
            depth: self.clear_depth,
            reference: None,
            weights: vec![0.0; n],
            coverage: 0.0,
            joined: [0, 0],
            ambiguous,
        };
        if self.settings.layers != 2 || !first.complex {
            return none(first.ambiguous);
        }
        let keys = self.keys(px);
        let outside: Vec<bool> = first.weights.iter().map(|&w| w == 0.0).collect();
        let mut ambiguous = first.ambiguous;
        let r = first.reference;
        // (sample, outside the reference's depth window, cluster size)
        let mut seed: Option<(usize, bool, usize)> = None;
        for s in (0..n).filter(|&s| outside[s]) {
            let mut size = 0;
            for j in (0..n).filter(|&j| outside[j]) {
                let (inside, unsure) = self.member(px, &keys, j, s);
                size += usize::from(inside);
                ambiguous |= unsure;
            }
            let (w, near_edge) = self.closeness(&keys, s, r);
            let apart = w == 0.0;
            ambiguous |= near_edge;
            let better = match seed {
                None => true,
                Some((b, b_apart, best)) => {
                    (apart && !b_apart)
                        || (apart == b_apart && (size > best || (size == best && keys.less(s, b))))
                }
            };
            if better {
                seed = Some((s, apart, size));
            }
        }
        let Some((s, _, n2)) = seed else {
            return none(ambiguous);
        };
        let weights: Vec<f64> = (0..n)
            .map(|j| {
                if outside[j] && self.member(px, &keys, j, s).0 {
                    self.closeness(&keys, j, s).0
                } else {
                    0.0
                }
            })
            .collect();
        let mut joined = [0, 0];
        for j in (0..n).filter(|&j| outside[j] && !self.member(px, &keys, j, s).0) {
            let (second, unsure) = self.joins_second(px, &keys, j, r, s);
            joined[usize::from(second)] += 1;
            ambiguous |= unsure;
        }
        let attachments = px
            .attachments
            .iter()
            .zip(&self.rules)
            .map(|(values, rule)| match rule {
                ResolveRule::Select => values[s],
                ResolveRule::Blend => blend(values, &weights, s),
                ResolveRule::BlendNormal => blend_normal(values, &weights, s),
                ResolveRule::BlendHdr => blend_hdr(values, &weights, s),
            })
            .collect();
        let depth = if self.settings.blend_depth {
            let sum: f64 = (0..n).map(|i| weights[i] * px.depth[i]).sum();
            sum / weights.iter().sum::<f64>()
        } else {
            px.depth[s]
        };
        SecondLayerPixel {
            attachments,
            depth,
            reference: Some(s),
            weights,
            coverage: (n2 + joined[1]) as f64 / n as f64,
            joined,
            ambiguous,
        }
    }
}

/// Weighted mean over finite samples; the reference's value when none weigh.
pub fn blend(values: &[[f64; 4]], weights: &[f64], r: usize) -> [f64; 4] {
    if let Some(v) = equal_contributions(values, weights) {
        return v;
    }
    let mut sum = [0.0; 4];
    let mut weight = 0.0;
    for (x, &w) in values.iter().zip(weights) {
        if w > 0.0 && is_finite4(x) {
            for c in 0..4 {
                sum[c] += w * x[c];
            }
            weight += w;
        }
    }
    if weight > 0.0 {
        sum.map(|s| s / weight)
    } else {
        values[r]
    }
}

/// The value every contributing sample (weight above 0, finite) has, when
/// they all have the same one: a blend of equal values is that value.
fn equal_contributions(values: &[[f64; 4]], weights: &[f64]) -> Option<[f64; 4]> {
    let mut used = values
        .iter()
        .zip(weights)
        .filter(|(x, w)| **w > 0.0 && is_finite4(x))
        .map(|(x, _)| *x);
    let first = used.next()?;
    used.all(|x| x == first).then_some(first)
}

/// xyz: the normalised weighted sum (the reference's xyz when it is shorter
/// than 1e-6); w: blended like [`blend`]. Equal contributions are that
/// value, as in [`blend`]: a pixel whose samples are one surface keeps the
/// host's normal as it wrote it, normalised or not.
pub fn blend_normal(values: &[[f64; 4]], weights: &[f64], r: usize) -> [f64; 4] {
    if let Some(v) = equal_contributions(values, weights) {
        return v;
    }
    let mean = blend(values, weights, r);
    let mut n = [0.0; 3];
    for (x, &w) in values.iter().zip(weights) {
        if w > 0.0 && is_finite4(x) {
            for c in 0..3 {
                n[c] += w * x[c];
            }
        }
    }
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len >= 1e-6 {
        [n[0] / len, n[1] / len, n[2] / len, mean[3]]
    } else {
        [values[r][0], values[r][1], values[r][2], mean[3]]
    }
}

/// Blend in the tonemapped domain `T(x) = x / (1 + m)`, `m = max(max3(x), 0)`,
/// map back with `T⁻¹(y) = y / (1 − max3(y))`, and clamp to the contributing
/// samples' per-channel range; alpha blends linearly. `1 − max3(y)` is
/// accumulated directly as the smallest blended `(1 + m − x) / (1 + m)`, which
/// is the same value without the cancellation near 65504.
pub fn blend_hdr(values: &[[f64; 4]], weights: &[f64], r: usize) -> [f64; 4] {
    let mut sum = [0.0; 3];
    let mut complement = [0.0; 3];
    let mut alpha = 0.0;
    let mut weight = 0.0;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (x, &w) in values.iter().zip(weights) {
        if w > 0.0 && is_finite4(x) {
            let m = max3(x).max(0.0);
            for c in 0..3 {
                sum[c] += w * x[c] / (1.0 + m);
                complement[c] += w * (1.0 + m - x[c]) / (1.0 + m);
                lo[c] = lo[c].min(x[c]);
                hi[c] = hi[c].max(x[c]);
            }
            alpha += w * x[3];
            weight += w;
        }
    }
    if weight <= 0.0 {
        return values[r];
    }
    // Both sums carry the same 1/weight, which cancels in the quotient; the
    // weight itself bounds the complement for all-negative colours (m = 0).
    let denominator = complement[0]
        .min(complement[1])
        .min(complement[2])
        .min(weight)
        .max(1e-30);
    [
        (sum[0] / denominator).clamp(lo[0], hi[0]),
        (sum[1] / denominator).clamp(lo[1], hi[1]),
        (sum[2] / denominator).clamp(lo[2], hi[2]),
        equal_contributions(values, weights).map_or(alpha / weight, |v| v[3]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resolver(method: ResolveMethod, window: Window) -> CpuResolve {
        CpuResolve {
            settings: ResolveSettings {
                method,
                window,
                ..ResolveSettings::default()
            },
            rules: vec![ResolveRule::Blend, ResolveRule::Blend],
            key_source: CpuKeySource::Position(1),
            clear_depth: 1.0,
            footprint: 0.001,
            normal: None,
        }
    }

    /// Colour = sample index, position z = −depths[i].
    fn pixel(depths: &[f64]) -> PixelSamples {
        PixelSamples {
            depth: depths
                .iter()
                .map(|&z| if z.is_infinite() { 1.0 } else { 0.5 })
                .collect(),
            attachments: vec![
                (0..depths.len())
                    .map(|i| [i as f64, 0.0, 0.0, 1.0])
                    .collect(),
                depths.iter().map(|&z| [0.0, 0.0, -z, 1.0]).collect(),
            ],
        }
    }

    #[test]
    fn median_is_the_median_by_depth_not_by_index() {
        // Sorted by depth the samples are 3, 1, 0, 2: position 2 is sample 0.
        // An index-comparing network (FreeSpace Open's bug) would return sample 2.
        let cpu = resolver(ResolveMethod::Median, Window::Hard);
        let px = pixel(&[30.0, 20.0, 40.0, 10.0]);
        assert_eq!(cpu.resolve_pixel(&px).reference, 0);
        let px = pixel(&[5.0, 9.0, 1.0, 7.0, 3.0, 8.0, 2.0, 6.0]);
        // Sorted: 1(s2) 2(s6) 3(s4) 5(s0) 6(s7) 7(s3) 8(s5) 9(s1); position 4 is s7.
        assert_eq!(cpu.resolve_pixel(&px).reference, 7);
    }

    #[test]
    fn ties_break_to_the_lower_index() {
        let px = pixel(&[10.0, 5.0, 5.0, 10.0]);
        assert_eq!(
            resolver(ResolveMethod::Front, Window::Hard)
                .resolve_pixel(&px)
                .reference,
            1
        );
        assert_eq!(
            resolver(ResolveMethod::Back, Window::Hard)
                .resolve_pixel(&px)
                .reference,
            0
        );
        // Sorted (z, i): s1 s2 s0 s3 → position 2 is s0.
        assert_eq!(
            resolver(ResolveMethod::Median, Window::Hard)
                .resolve_pixel(&px)
                .reference,
            0
        );
    }

    #[test]
    fn background_majority_resolves_to_background() {
        let inf = f64::INFINITY;
        let px = pixel(&[10.0, inf, inf, inf]);
        let out = resolver(ResolveMethod::Median, Window::Smooth).resolve_pixel(&px);
        assert_eq!(out.weights, vec![0.0, 1.0, 1.0, 1.0]);
        assert_eq!(out.attachments[0][0], 2.0); // mean of samples 1..3
        assert_eq!(out.depth, 1.0);
    }

    #[test]
    fn hard_window_blends_only_close_samples() {
        // footprint at z=100: 0.1 → c·m = 0.5.
        let px = pixel(&[100.0, 100.4, 100.6, 300.0]);
        let out = resolver(ResolveMethod::Front, Window::Hard).resolve_pixel(&px);
        assert_eq!(out.reference, 0);
        assert_eq!(out.weights, vec![1.0, 1.0, 0.0, 0.0]);
        assert_eq!(out.attachments[0][0], 0.5);
    }

    #[test]
    fn smooth_window_ramps() {
        // c_in·m = 0.25, c·m = 0.5 at z = 100.
        let px = pixel(&[100.0, 100.2, 100.375, 100.6]);
        let out = resolver(ResolveMethod::Front, Window::Smooth).resolve_pixel(&px);
        assert_eq!(out.weights[1], 1.0);
        assert!((out.weights[2] - 0.5).abs() < 1e-9, "{:?}", out.weights);
        assert_eq!(out.weights[3], 0.0);
    }

    #[test]
    fn average_weighs_everything() {
        let inf = f64::INFINITY;
        let px = pixel(&[1.0, 100.0, inf, 7.0]);
        let out = resolver(ResolveMethod::Average, Window::Hard).resolve_pixel(&px);
        assert_eq!(out.weights, vec![1.0; 4]);
        assert_eq!(out.attachments[0][0], 1.5);
    }

    #[test]
    fn fast_path_takes_sample_zero() {
        let mut px = pixel(&[10.0; 4]);
        px.attachments[0][1] = [9.0, 9.0, 9.0, 9.0];
        let cpu = resolver(ResolveMethod::Median, Window::Smooth);
        let out = cpu.resolve_pixel(&px);
        assert!(!out.complex);
        assert_eq!(out.attachments[0], px.attachments[0][0]);
        let mut slow = cpu.clone();
        slow.settings.fast_path = false;
        let out = slow.resolve_pixel(&px);
        assert!(out.complex);
        assert_eq!(out.attachments[0][0], (0.0 + 9.0 + 2.0 + 3.0) / 4.0);
    }

    #[test]
    fn non_finite_values_are_skipped() {
        let mut px = pixel(&[10.0; 4]);
        px.attachments[0][2] = [f64::NAN, 0.0, 0.0, 1.0];
        let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
        cpu.settings.fast_path = false;
        let out = cpu.resolve_pixel(&px);
        assert_eq!(out.attachments[0][0], (0.0 + 1.0 + 3.0) / 3.0);
    }

    #[test]
    fn equal_normals_are_kept_as_written() {
        // Not unit length (a gloss-scaled normal): one surface's samples
        // resolve to it unchanged, as the host's own render holds it.
        let n = [0.3, 0.1, 0.2, 0.7];
        assert_eq!(blend_normal(&[n, n, n], &[1.0, 0.5, 1.0], 0), n);
    }

    #[test]
    fn opposite_normals_fall_back_to_the_reference() {
        let values = vec![[0.0, 0.0, 1.0, 0.3], [0.0, 0.0, -1.0, 0.5]];
        let out = blend_normal(&values, &[1.0, 1.0], 1);
        assert_eq!(out, [0.0, 0.0, -1.0, 0.4]);
    }

    #[test]
    fn hdr_blend_stays_finite_and_in_range() {
        let values = vec![[65504.0, 65504.0, 65504.0, 1.0], [65504.0, 0.0, 1.0, 1.0]];
        let out = blend_hdr(&values, &[1.0, 1.0], 0);
        assert!(out.iter().all(|c| c.is_finite()));
        assert!(out[0] <= 65504.0 && out[0] >= 65504.0 * 0.99);
        let one = blend_hdr(&values[..1], &[1.0], 0);
        assert_eq!(one[0], 65504.0);
    }

    #[test]
    fn depth_keys_from_the_projection() {
        // Standard GL projection terms for near 0.1, far 100.
        let (n, f) = (0.1, 100.0);
        let dp = DepthProjection {
            p22: -(f + n) / (f - n),
            p23: -2.0 * f * n / (f - n),
            zero_to_one: false,
            clear_depth: 1.0,
        };
        // A point at distance 10: z_clip = p22·(−10) + p23, w = 10.
        let z_ndc = (dp.p22 * -10.0 + dp.p23) / 10.0;
        let depth = (z_ndc + 1.0) * 0.5;
        assert!((dp.linearize(depth) - 10.0).abs() < 1e-9);
        assert!((dp.linearize(0.0) - n).abs() < 1e-12);
        assert!((dp.linearize(1.0) - f).abs() < 1e-9);
        // Reversed-Z with an infinite far plane and GL_ZERO_TO_ONE: depth = n / z.
        let rev = DepthProjection {
            p22: 0.0,
            p23: n,
            zero_to_one: true,
            clear_depth: 0.0,
        };
        assert!((rev.linearize(n / 10.0) - 10.0).abs() < 1e-9);
        assert!(rev.linearize(0.0).is_infinite());
    }

    #[test]
    fn the_second_layer_is_the_largest_other_cluster_sharing_with_the_first() {
        let inf = f64::INFINITY;
        let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
        cpu.settings.layers = 2;
        // A bar (z = 10) over the sky: median takes the sky (samples 1..3),
        // the second layer is the bar's one sample.
        let out = cpu.resolve_second_layer_at(&pixel(&[10.0, inf, inf, inf]), None);
        assert_eq!(out.reference, Some(0));
        assert_eq!(out.coverage, 0.25);
        assert_eq!(out.weights, vec![1.0, 0.0, 0.0, 0.0]);
        // Three clusters (10, 50, 200): the median's (50, samples 1 and 2),
        // then the largest of the rest, ties to the nearer: 10 (sample 0).
        let px = pixel(&[10.0, 50.0, 50.0, 200.0]);
        let first = cpu.resolve_pixel(&px);
        assert_eq!(first.weights, vec![0.0, 1.0, 1.0, 0.0]);
        let out = cpu.resolve_second_layer_at(&px, None);
        assert_eq!(out.reference, Some(0));
        // Sample 3 (200) is in neither: it joins the nearer in depth, the
        // first (50 is 150 away, 10 is 190), so the second keeps 1 of 4.
        assert_eq!((out.coverage, out.joined), (0.25, [1, 0]));
        // A third cluster nearer the second (12 beside 10): it joins the
        // second, which then holds 2 of 4.
        let out = cpu.resolve_second_layer_at(&pixel(&[10.0, 12.0, 50.0, 50.0]), None);
        assert_eq!(out.reference, Some(0));
        assert_eq!(out.weights, vec![1.0, 0.0, 0.0, 0.0]);
        assert_eq!((out.coverage, out.joined), (0.5, [0, 1]));
        // One cluster: no second layer, sample 0's values at the clear depth.
        let out = cpu.resolve_second_layer_at(&pixel(&[10.0, 10.01, 10.0, 10.02]), None);
        assert_eq!((out.reference, out.coverage, out.depth), (None, 0.0, 1.0));
    }

    #[test]
    fn normals_split_a_crease_with_one_layer_or_two() {
        let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
        // One depth, two orientations 90 degrees apart (attachment 0 holds
        // the normals here): samples 0, 1 face +z, samples 2, 3 face +x.
        let mut px = pixel(&[10.0, 10.01, 10.0, 10.01]);
        px.attachments[0] = vec![
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
        ];
        // By depth alone the crease is one surface.
        assert_eq!(cpu.resolve_pixel(&px).weights, vec![1.0; 4]);
        // With the normals named it is two, with one layer and with two.
        cpu.normal = Some((0, NormalEncoding::Xyz));
        assert_eq!(cpu.resolve_pixel(&px).weights, vec![1.0, 1.0, 0.0, 0.0]);
        cpu.settings.layers = 2;
        let first = cpu.resolve_pixel(&px);
        assert_eq!(first.weights, vec![1.0, 1.0, 0.0, 0.0]);
        let second = cpu.resolve_second_layer_at(&px, None);
        assert_eq!(second.reference, Some(2));
        assert_eq!(second.coverage, 0.5);
    }

    #[test]
    fn a_side_sliver_joins_its_front_face_not_the_wall() {
        // A thin box's silhouette pixel: its front face (+z, sample 0), its
        // side face 0.06 behind it (+x, sample 1), a far wall (samples 2, 3).
        let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
        cpu.settings.layers = 2;
        cpu.normal = Some((0, NormalEncoding::Xyz));
        let mut px = pixel(&[10.0, 10.06, 200.0, 200.0]);
        px.attachments[0] = vec![
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        // The median is the wall; the front face and the side are two
        // clusters of one sample, of which the nearer is the second layer.
        assert_eq!(cpu.resolve_pixel(&px).weights, vec![0.0, 0.0, 1.0, 1.0]);
        let second = cpu.resolve_second_layer_at(&px, None);
        assert_eq!(second.reference, Some(0));
        assert_eq!(second.weights, vec![1.0, 0.0, 0.0, 0.0]);
        // The side joins the front face (0.06 away, the wall 189.94): the
        // box keeps its two samples' share, and its layer the front
        // face's values alone.
        assert_eq!((second.coverage, second.joined), (0.5, [0, 1]));
        // Equal distances go by orientation: a sample midway in depth that
        // faces like the wall joins the first layer, like the bar the
        // second.
        let mut px = pixel(&[10.0, 105.0, 200.0, 200.0]);
        px.attachments[0] = vec![
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.6, 0.8, 0.0],
            [0.0, 0.8, 0.6, 0.0],
            [0.0, 0.8, 0.6, 0.0],
        ];
        let out = cpu.resolve_second_layer_at(&px, None);
        assert_eq!((out.reference, out.joined), (Some(0), [1, 0]));
        px.attachments[0][1] = [0.0, 0.28, 0.96, 0.0];
        let out = cpu.resolve_second_layer_at(&px, None);
        assert_eq!((out.reference, out.joined), (Some(0), [0, 1]));
    }

    #[test]
    fn with_two_layers_the_reference_moves_to_the_larger_face() {
        // Front face twice, the side just behind it once, the wall: the
        // median is the side (the 3rd of 4 by depth).
        let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
        cpu.normal = Some((0, NormalEncoding::Xyz));
        let mut px = pixel(&[10.0, 10.0, 10.001, 200.0]);
        px.attachments[0] = vec![
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        // One layer keeps the median's face.
        assert_eq!(cpu.resolve_pixel(&px).reference, 2);
        // Two: the front face, which two samples share, is the first layer,
        // the wall (another depth) the second, and the side joins the first.
        cpu.settings.layers = 2;
        let first = cpu.resolve_pixel(&px);
        assert_eq!(
            (first.reference, first.weights),
            (0, vec![1.0, 1.0, 0.0, 0.0])
        );
        let second = cpu.resolve_second_layer_at(&px, None);
        assert_eq!(second.reference, Some(3));
        assert_eq!((second.coverage, second.joined), (0.25, [1, 0]));
    }

    #[test]
    fn normal_encodings_decode_to_the_stored_direction() {
        let n = [0.48, -0.6, -0.64];
        let unorm = [n[0] * 0.5 + 0.5, n[1] * 0.5 + 0.5, n[2] * 0.5 + 0.5, 0.0];
        let d = NormalEncoding::Unorm.decode(unorm);
        assert!((0..3).all(|c| (d[c] - n[c]).abs() < 1e-12));
        // Octahedral: project onto |x| + |y| + |z| = 1, fold the lower half.
        let l1 = n[0].abs() + n[1].abs() + n[2].abs();
        let (px, py) = (n[0] / l1, n[1] / l1);
        let sign = |c: f64| if c >= 0.0 { 1.0 } else { -1.0 };
        let folded = [(1.0 - py.abs()) * sign(px), (1.0 - px.abs()) * sign(py)];
        for (encoding, stored) in [
            (NormalEncoding::Octahedral, [folded[0], folded[1], 0.0, 0.0]),
            (
                NormalEncoding::OctahedralUnorm,
                [folded[0] * 0.5 + 0.5, folded[1] * 0.5 + 0.5, 0.0, 0.0],
            ),
        ] {
            let d = encoding.decode(stored);
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            assert!(
                (0..3).all(|c| (d[c] / len - n[c]).abs() < 1e-9),
                "{encoding}: {d:?}"
            );
        }
    }
}
