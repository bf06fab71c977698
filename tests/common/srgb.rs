//! The sRGB transfer function in f64, for tests that compute an expected
//! 8-bit value by hand and compare it within a tolerance (the lab's
//! `compare::srgb_to_linear` is f32, for measuring images).

/// An 8-bit sRGB value as linear light, 0 to 1.
pub fn decode(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light (clamped to 0 to 1) as an sRGB value on the 8-bit scale,
/// 0 to 255, not rounded.
pub fn encode(l: f64) -> f64 {
    let l = l.clamp(0.0, 1.0);
    255.0
        * if l <= 0.003_130_8 {
            l * 12.92
        } else {
            1.055 * l.powf(1.0 / 2.4) - 0.055
        }
}
