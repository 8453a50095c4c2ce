//! The per-frame outputs of a scene raster pass, and their formats (one place).

use cbr_gpu::{Gpu, Image, ImageDesc, Result, vk};

use crate::memory::MemoryEstimate;

pub const COLOR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const VELOCITY_FORMAT: vk::Format = vk::Format::R32G32_SFLOAT;
pub const ID_FORMAT: vk::Format = vk::Format::R32G32_UINT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// `deferred`'s G-buffer surface layers (position, normal, albedo) and its reflective shadow map:
/// f32, so the lighting pass shades the forward pass's exact inputs.
pub const GBUFFER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Bytes of one sample across the four targets: RGBA16F + RG32F + RG32UI + D32.
pub const BYTES_PER_SAMPLE: u64 = 8 + 8 + 8 + 4;

/// Colour (HDR), velocity (pixels), IDs (object, primitive) and reverse-Z depth.
pub struct FrameTargets {
    pub color: Image,
    pub velocity: Image,
    pub ids: Image,
    pub depth: Image,
}

impl FrameTargets {
    /// Velocity, depth and IDs for temporal post passes.
    pub fn geometry(&self) -> crate::frame::Geometry<'_> {
        crate::frame::Geometry {
            velocity: &self.velocity,
            depth: &self.depth,
            ids: &self.ids,
            packed: false,
        }
    }

    /// `binds` with the four targets under the names the passes that read a raster use
    /// (`color`, `velocity`, `ids`, `depth`: crate::pass).
    pub fn bind<'a>(&'a self, binds: crate::pass::Binds<'a>) -> crate::pass::Binds<'a> {
        binds
            .image("color", &self.color)
            .image("velocity", &self.velocity)
            .image("ids", &self.ids)
            .image("depth", &self.depth)
    }

    /// The colour attachments in the scene pipeline's order.
    pub fn colors(&self) -> [&Image; 3] {
        [&self.color, &self.velocity, &self.ids]
    }

    /// Colour, depth, velocity and IDs: the order of the common layers (techniques::LayerReadbacks).
    pub fn layers(&self) -> [&Image; 4] {
        [&self.color, &self.depth, &self.velocity, &self.ids]
    }

    /// Bytes of the four targets (every layer and sample).
    pub fn bytes(&self) -> u64 {
        let t = &self.color;
        u64::from(t.width)
            * u64::from(t.height)
            * u64::from(t.layers)
            * u64::from(t.samples)
            * BYTES_PER_SAMPLE
    }

    /// What [`FrameTargets::layered`] allocates (crate::memory).
    pub fn estimate(
        e: &mut MemoryEstimate,
        prefix: &str,
        width: u32,
        height: u32,
        layers: u32,
        samples: u32,
    ) {
        for (name, format) in [
            ("color", COLOR_FORMAT),
            ("velocity", VELOCITY_FORMAT),
            ("ids", ID_FORMAT),
            ("depth", DEPTH_FORMAT),
        ] {
            let name = format!("{prefix}.{name}");
            e.image_array(name, format, width, height, layers, samples);
        }
    }

    /// Single-layer, single-sample targets (the native technique).
    pub fn new(gpu: &Gpu, prefix: &str, width: u32, height: u32) -> Result<FrameTargets> {
        FrameTargets::layered(gpu, prefix, width, height, 1, 1, false)
    }

    /// Targets with `layers` array layers and `samples` samples each (checkerboard layouts);
    /// `sample_locations`: a depth target compatible with custom sample locations (msaa2x with
    /// VK_EXT_sample_locations).
    pub fn layered(
        gpu: &Gpu,
        prefix: &str,
        width: u32,
        height: u32,
        layers: u32,
        samples: u32,
        sample_locations: bool,
    ) -> Result<FrameTargets> {
        // TRANSFER_DST: tests upload synthetic samples (the resolve's CPU-reference test).
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::SAMPLED;
        let img = |name: &str, format, usage| {
            let name = format!("{prefix}.{name}");
            let mut d = ImageDesc::new_2d(&name, format, width, height, usage);
            d.layers = layers;
            d.samples = samples;
            if sample_locations && format == DEPTH_FORMAT {
                d.flags = vk::ImageCreateFlags::SAMPLE_LOCATIONS_COMPATIBLE_DEPTH_EXT;
            }
            Image::new(gpu, &d)
        };
        Ok(FrameTargets {
            color: img("color", COLOR_FORMAT, usage)?,
            velocity: img("velocity", VELOCITY_FORMAT, usage)?,
            ids: img("ids", ID_FORMAT, usage)?,
            depth: img(
                "depth",
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::SAMPLED,
            )?,
        })
    }
}
