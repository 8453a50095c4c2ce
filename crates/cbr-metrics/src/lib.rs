//! Image I/O (multi-layer EXR, PNG), the display transform, and the image metrics. No Vulkan.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod display;
pub mod io;

pub use display::DisplayTransform;
