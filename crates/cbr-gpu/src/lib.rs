//! cbr's Vulkan layer. Every `unsafe` block of the project lives in this crate, each with a
//! `// SAFETY:` line. Other crates use the safe API: `Gpu`, resources, `Cmd`, pipelines, queries.
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod access;
pub mod caps;
pub mod cmd;
mod context;
pub mod error;
pub mod executables;
pub mod null_device;
pub mod pipeline;
pub mod query;
pub mod resource;
pub mod select;
pub mod shaders;

pub use access::Access;
pub use ash::vk;
pub use caps::{Caps, Layout};
pub use cmd::{Attachment, Cmd, LevelCopy};
pub use context::{DeviceInfo, DeviceReport, Gpu, GpuOptions, ValidationLog};
pub use error::{GpuError, Result};
pub use executables::{CompileSettings, ExecutableStats, PipelineExecutables, StatValue};
pub use pipeline::{
    BindingDesc, ComputeDesc, DescriptorKind, DescriptorSet, GraphicsDesc, Pipeline, SetLayout,
    Write,
};
pub use query::{PassKind, PassTiming, PipelineStats, Profiler, Traffic};
pub use resource::{Buffer, Image, ImageDesc, Location, Readback, Sampler, SamplerDesc};
pub use shaders::{
    DirTree, Request, Shaders, SourceTree, StaticTree, referenced_bindings, semantic_words,
};
