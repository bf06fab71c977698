//! The second layer in the CPU reference: the normal test, the clusters'
//! seeds, the first layer's reference with two layers, and the samples of
//! neither kept cluster (`resolve.frag`'s `SECOND_LAYER_OUTPUT` and
//! `MAJORITY_REFERENCE`).

use super::{CpuKeySource, CpuResolve, Keys, PixelPlace, PixelSamples, SecondLayerPixel};
use super::{blend, blend_hdr, blend_normal};
use crate::resolve::{NormalEncoding, ResolveMethod, ResolveRule};

impl CpuResolve {
    /// Whether clusters split by normal: a normal attachment, with one
    /// layer or two.
    pub(super) fn splits_by_normal(&self) -> Option<(usize, NormalEncoding)> {
        self.normal
    }

    /// Whether samples `i` and `j` may be one surface by their normals (always,
    /// without the normal test, for background, or for a normal that is not
    /// finite or shorter than 1e-6), and whether `f32` may decide it
    /// differently (a cosine within 1e-5 of the threshold).
    pub(super) fn same_normal(
        &self,
        px: &PixelSamples,
        keys: &Keys,
        i: usize,
        j: usize,
    ) -> (bool, bool) {
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

    /// With a normal attachment (one layer or two; any method but
    /// `Average`), the reference `r` moves to the sample within its depth
    /// window whose cluster (the samples within its window and of its
    /// orientation) is the largest, if larger than its own: the first of
    /// those in index order. A crease, or a box's side face just behind its
    /// front face, can put the median on the smaller face; the larger's
    /// samples would then join it and be lit as it. Where no cluster is
    /// larger than the reference's but another within its window is as
    /// large (a crease through the middle of the pixel), the reference
    /// goes to the face the pixel centre sees where the crease rule
    /// ([`crease_side`](Self::crease_side)) knows it; otherwise it stays on
    /// pixels of even parity and moves to the first sample of that other
    /// face on odd ones ([`odd_pixel`](super::odd_pixel)).
    /// The second value: `f32` may decide differently.
    pub(super) fn majority_reference(
        &self,
        px: &PixelSamples,
        keys: &Keys,
        r: usize,
        at: Option<PixelPlace>,
    ) -> (usize, bool) {
        if self.splits_by_normal().is_none() || self.settings.method == ResolveMethod::Average {
            return (r, false);
        }
        let n = px.depth.len();
        let mut ambiguous = false;
        let mut member = |j: usize, s: usize| {
            let (inside, unsure) = self.member(px, keys, j, s);
            ambiguous |= unsure;
            inside
        };
        let sizes: Vec<usize> = (0..n)
            .map(|s| (0..n).filter(|&j| member(j, s)).count())
            .collect();
        let apart: Vec<bool> = (0..n).map(|s| !member(s, r)).collect();
        let odd = super::odd_pixel(at);
        let mut best = r;
        let mut tied: Option<usize> = None;
        for s in 0..n {
            let (w, near_edge) = self.closeness(keys, s, r);
            ambiguous |= near_edge;
            if w > 0.0 && sizes[s] > sizes[best] {
                best = s;
            }
            if w > 0.0 && sizes[s] == sizes[r] && apart[s] && tied.is_none() {
                tied = Some(s);
            }
        }
        // A tie between the reference's face and another: the face the
        // pixel centre sees where the crease rule knows it; otherwise the
        // median's on pixels of even parity, the other on odd ones.
        if let (true, Some(t)) = (best == r, tied) {
            // (Membership's own f32 doubts were counted with the sizes.)
            let in_r: Vec<bool> = (0..n).map(|j| self.member(px, keys, j, r).0).collect();
            let in_t: Vec<bool> = (0..n).map(|j| self.member(px, keys, j, t).0).collect();
            let (side, unsure) = self.crease_side(px, (r, &in_r), (t, &in_t), at);
            ambiguous |= unsure;
            if side.map_or(odd, |on_r| !on_r) {
                best = t;
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
    /// `joins_second` says, for the coverage only:
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
