//! Will a layout hold a scene? FP16 positions overflow beyond 65504 units,
//! and a depth buffer's steps grow with the square of the distance
//! (standard projection) until near and far surfaces share one value or
//! geometry rounds to the clear depth. Checked before rendering, so the
//! user is warned instead of silently losing a distant model.

use super::GBufferLayout;
use crate::gl::Format;

/// The depth mapping a frame uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthSetup {
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance; `None` for an infinite far plane.
    pub far: Option<f64>,
    /// Reversed-Z (near → 1, far → 0) with `GL_ZERO_TO_ONE` depth.
    pub reversed: bool,
}

/// Largest finite half float.
pub const HALF_MAX: f64 = 65504.0;

/// The smallest view-distance difference the depth buffer resolves at
/// distance `z`, and whether geometry there rounds to the clear depth.
pub fn depth_resolution(format: Format, setup: &DepthSetup, z: f64) -> (f64, bool) {
    let n = setup.near;
    // d(z) and |dd/dz| for the four mappings.
    let (d, slope) = match (setup.reversed, setup.far) {
        (false, Some(f)) => {
            let d = 0.5 * ((f + n) / (f - n) - 2.0 * f * n / ((f - n) * z)) + 0.5;
            (d, f * n / ((f - n) * z * z))
        }
        (false, None) => (1.0 - n / z, n / (z * z)),
        (true, Some(f)) => (n * (f - z) / (z * (f - n)), n * f / ((f - n) * z * z)),
        (true, None) => (n / z, n / (z * z)),
    };
    let clear = if setup.reversed { 0.0 } else { 1.0 };
    let step = match format {
        Format::Depth16 => 1.0 / 65535.0,
        Format::Depth24 | Format::Depth24Stencil8 => 1.0 / 16_777_215.0,
        // A float's spacing at d: 2^-23 of its magnitude (denormals aside).
        _ => (d.abs() * f64::from(f32::EPSILON)).max(f64::from(f32::MIN_POSITIVE)),
    };
    let lost = (d - clear).abs() < step * 0.5;
    (step / slope, lost)
}

/// Warnings for a layout drawing geometry out to `max_distance` units from
/// the camera: FP16 position overflow, and depth too coarse to tell
/// surfaces `detail` units apart (or losing them to background).
pub fn precision_warnings(
    layout: &GBufferLayout,
    setup: &DepthSetup,
    max_distance: f64,
    detail: f64,
) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(position) = layout
        .attachment("position")
        .or_else(|| layout.key_attachment())
    {
        if position.format.is_half_float() && max_distance > HALF_MAX {
            warnings.push(format!(
                "attachment `{}` ({}) overflows beyond {HALF_MAX} units but the scene reaches {max_distance:.0}: \
                 distant geometry would become infinite and resolve as background; use RGBA32F (the recommended layout)",
                position.name, position.format
            ));
        }
    }
    let (resolution, lost) = depth_resolution(layout.depth, setup, max_distance);
    if lost {
        warnings.push(format!(
            "depth {} rounds geometry at {max_distance:.0} units to the clear depth: it would resolve as background; \
             use 32-bit float depth with reversed-Z (the recommended layout)",
            layout.depth
        ));
    } else if resolution > detail {
        warnings.push(format!(
            "depth {} cannot separate surfaces closer than {resolution:.3} units at {max_distance:.0} units \
             (detail of {detail:.3} units merges); use 32-bit float depth with reversed-Z (the recommended layout)",
            layout.depth
        ));
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    const FAR_MODEL: DepthSetup = DepthSetup {
        near: 0.01,
        far: Some(1.0e6),
        reversed: false,
    };

    #[test]
    fn freespace_open_layout_cannot_hold_a_model_200_km_away() {
        let w = precision_warnings(&GBufferLayout::freespace_open(), &FAR_MODEL, 200_000.0, 1.0);
        assert_eq!(w.len(), 2, "{w:#?}");
        assert!(w[0].contains("65504") && w[0].contains("position"));
        assert!(w[1].contains("DEPTH_COMPONENT24"));
    }

    #[test]
    fn reversed_float_depth_keeps_it() {
        let setup = DepthSetup {
            reversed: true,
            ..FAR_MODEL
        };
        let w = precision_warnings(&GBufferLayout::recommended(), &setup, 200_000.0, 1.0);
        assert!(w.is_empty(), "{w:#?}");
        let (res, lost) = depth_resolution(Format::Depth32f, &setup, 200_000.0);
        assert!(!lost && res < 0.1, "{res}");
        // Standard float depth is no better than D24 there: d sits next to 1.0.
        let (_, lost) = depth_resolution(Format::Depth32f, &FAR_MODEL, 200_000.0);
        let (res, _) = depth_resolution(Format::Depth32f, &FAR_MODEL, 200_000.0);
        assert!(lost || res > 1.0, "{res}");
    }

    #[test]
    fn ordinary_scenes_are_fine() {
        let setup = DepthSetup {
            near: 0.1,
            far: Some(1000.0),
            reversed: false,
        };
        assert!(
            precision_warnings(&GBufferLayout::freespace_open(), &setup, 200.0, 0.05).is_empty()
        );
    }
}
