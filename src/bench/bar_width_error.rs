//! Why a bar's width cannot be measured ([`BarWidthError`], public as
//! `bench::bar_width::BarWidthError`). A module of its own, naming nothing
//! of the crate, so that the lab's [`Error`](crate::Error) can wrap it
//! without depending on the bar width measure and, through it, the scenes.

/// Why a bar's width cannot be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BarWidthError {
    /// There is no bar.
    #[error("no bars to measure")]
    NoBars,
    /// A point of the bar is not in front of the camera.
    #[error("bar {bar}: not in front of the camera")]
    NotInView {
        /// The bar's index.
        bar: usize,
    },
    /// No band of the bar lies wholly inside the image.
    #[error(
        "bar {bar}: no scanline across its measured stretch lies wholly inside the {width}x{height} image"
    )]
    OutsideImage {
        /// The bar's index.
        bar: usize,
        /// The image width.
        width: u32,
        /// The image height.
        height: u32,
    },
    /// The reference shows the bar too close in luminance to what is
    /// behind it (below [`MIN_CONTRAST`](super::bar_width::MIN_CONTRAST)).
    #[error(
        "bar {bar}: too little contrast to measure its width (linear luminance {bar_luminance:.3} on {behind_luminance:.3} in the reference)"
    )]
    LowContrast {
        /// The bar's index.
        bar: usize,
        /// The bar's luminance as estimated from the reference.
        bar_luminance: f64,
        /// The luminance behind it.
        behind_luminance: f64,
    },
    /// The measured image is not the reference's size.
    #[error("the image is {width}x{height}, the reference {reference_width}x{reference_height}")]
    SizeMismatch {
        /// The measured image's width.
        width: u32,
        /// The measured image's height.
        height: u32,
        /// The reference's width.
        reference_width: u32,
        /// The reference's height.
        reference_height: u32,
    },
}
