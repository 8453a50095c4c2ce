//! cbr's passes and the frame sequencer. Each pass is a struct: `new()` builds its pipelines once,
//! `record()` records commands only.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod checkerboard;
pub mod gpu_scene;
pub mod gpu_types;
pub mod layouts;
pub mod native;
pub mod renderer;
pub mod resolve;
pub mod targets;
pub mod upscale;

pub use renderer::{FrameOutput, LodMode, RenderSettings, Renderer, Technique};
pub use resolve::{Mapping, ResolveMode, ResolveSettings};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shader_sources.rs"));
}

/// The shader library: the sources embedded at build time, or the folder named by
/// `CBR_SHADER_DIR` (for editing shaders without rebuilding).
pub fn shader_library() -> cbr_gpu::Shaders {
    match std::env::var_os("CBR_SHADER_DIR") {
        Some(dir) => cbr_gpu::Shaders::new(Box::new(cbr_gpu::DirTree(dir.into()))),
        None => cbr_gpu::Shaders::new(Box::new(cbr_gpu::StaticTree(embedded::SOURCES))),
    }
}
