//! The blends of the attachment rules, over one cluster's weights.

fn is_finite4(x: &[f64; 4]) -> bool {
    x.iter().all(|c| c.is_finite())
}

fn max3(x: &[f64; 4]) -> f64 {
    x[0].max(x[1]).max(x[2])
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
