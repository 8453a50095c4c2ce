//! cbr's passes, techniques and the frame sequencer. A technique is a chain of passes registered
//! in [`registry::TECHNIQUES`]; post passes in [`registry::POST_PASSES`]; the sequencer
//! ([`Renderer`]) runs a [`Spec`] of them. Each pass is a struct: `new()` builds its pipelines
//! once, `record()` records commands only.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod cache;
mod cpu_math;
pub mod frame;
pub mod gpu_scene;
pub mod gpu_types;
pub mod layouts;
pub mod memory;
pub mod pass;
pub mod post;
pub mod registry;
pub mod renderer;
pub mod resolve;
pub mod scene_pass;
pub mod spec;
pub mod targets;
pub mod technique;
pub mod techniques;

pub use frame::{ExrType, FrameOutput, Layer, LayerDecl, SampleType, Samples, Stat, StatDecl};
pub use renderer::{RenderSettings, Renderer};
pub use resolve::ResolveOutput;
pub use resolve::{Mapping, ResolveMode, ResolveSettings};
pub use spec::Spec;
pub use techniques::Coverage;
pub use techniques::analytic::AnalyticLayers;
pub use techniques::checkerboard::{self, CheckerboardConfig, LodMode};
pub use techniques::interleaved::InterleavedLayers;
pub use techniques::taau;
pub use techniques::upscale;

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
