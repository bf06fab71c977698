//! What both benches share beside the test kit (its toy host and random
//! scene): the `--size` parser and the quantile their statistics use.

/// `WIDTHxHEIGHT`, both at least 1 (a clap value parser).
pub fn parse_size(v: &str) -> Result<(u32, u32), String> {
    let (w, h) = v
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got `{v}`"))?;
    match (w.parse::<u32>(), h.parse::<u32>()) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(format!(
            "expected two whole numbers of at least 1, got `{v}`"
        )),
    }
}

/// Quantile `q` of sorted data, linear between order statistics (NaN for none).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q * (sorted.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}
