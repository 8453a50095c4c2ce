//! Image I/O (multi-layer EXR, PNG), the display transform, and the image metrics (PSNR, SSIM,
//! LDR- and HDR-FLIP, MSE, relMSE, sequences and flicker). No Vulkan; rayon.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod compare;
pub mod display;
pub mod error;
pub mod flip;
pub mod heatmap;
pub mod input;
pub mod io;
pub mod planes;
pub mod ssim;
pub mod stats;

pub use compare::{
    CompareOptions, Metric, PairResult, SequenceResult, compare_images, compare_sequences,
    display_error, display_values, mean_abs_change, signed_error,
};
pub use display::DisplayTransform;
pub use error::MetricsError;
pub use input::{Encoding, InputImage};
pub use planes::Rgb;
