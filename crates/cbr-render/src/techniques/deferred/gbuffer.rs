//! The G-buffer of `deferred` and `interleaved`.

use cbr_gpu::{Image, ImageDesc, Result, vk};

use crate::frame::Geometry;
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, GBUFFER_FORMAT, ID_FORMAT, VELOCITY_FORMAT};

/// The G-buffer (the scene pass's targets with GBUFFER) and the lit frame.
pub struct GBuffer {
    pub position: Image,
    pub normal: Image,
    pub albedo: Image,
    pub velocity: Image,
    pub ids: Image,
    pub depth: Image,
    /// RGBA16F, written by the lighting pass.
    pub color: Image,
}

impl GBuffer {
    pub fn new(gpu: &cbr_gpu::Gpu, prefix: &str, width: u32, height: u32) -> Result<GBuffer> {
        use vk::ImageUsageFlags as U;
        let img = |name: &str, format, usage| {
            let name = format!("{prefix}.{name}");
            Image::new(gpu, &ImageDesc::new_2d(&name, format, width, height, usage))
        };
        let attachment = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;
        Ok(GBuffer {
            position: img("position", GBUFFER_FORMAT, attachment)?,
            normal: img("normal", GBUFFER_FORMAT, attachment)?,
            albedo: img("albedo", GBUFFER_FORMAT, attachment)?,
            velocity: img("velocity", VELOCITY_FORMAT, attachment)?,
            ids: img("ids", ID_FORMAT, attachment)?,
            depth: img(
                "depth",
                DEPTH_FORMAT,
                U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC,
            )?,
            color: img(
                "color",
                COLOR_FORMAT,
                U::STORAGE | U::SAMPLED | U::TRANSFER_SRC,
            )?,
        })
    }

    /// The G-buffer pass's attachments under the scene pass's names.
    pub fn bind(&self) -> crate::pass::Binds<'_> {
        crate::pass::Binds::new()
            .image("position", &self.position)
            .image("normal", &self.normal)
            .image("albedo", &self.albedo)
            .image("velocity", &self.velocity)
            .image("ids", &self.ids)
            .image("depth", &self.depth)
    }

    /// Velocity, depth and IDs for temporal post passes.
    pub fn geometry(&self) -> Geometry<'_> {
        Geometry {
            velocity: &self.velocity,
            depth: &self.depth,
            ids: &self.ids,
            packed: false,
        }
    }

    /// Colour, depth, velocity, IDs: the common layers.
    pub fn layers(&self) -> [&Image; 4] {
        [&self.color, &self.depth, &self.velocity, &self.ids]
    }

    /// Bytes per pixel: three f32 RGBA surface layers, velocity, IDs, depth and the frame.
    pub const BYTES_PER_PIXEL: u64 = 3 * 16 + 8 + 8 + 4 + 8;
}
