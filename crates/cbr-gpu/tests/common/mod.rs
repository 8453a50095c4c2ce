//! What the cbr-gpu tests share.

use cbr_gpu::{Gpu, GpuOptions};

/// The test device (`CBR_TEST_DEVICE`, else the default choice) with validation on.
pub fn gpu() -> Gpu {
    Gpu::new(&GpuOptions {
        device: std::env::var("CBR_TEST_DEVICE").ok(),
        validation: true,
    })
    .expect("device")
}
