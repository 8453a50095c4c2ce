//! The G-buffer of `deferred` and `interleaved`.

use cbr_gpu::{Image, Result, vk};

use crate::pass::ResourceDecl;

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
    /// Its images: the scene pass's G-buffer attachments, and the lit frame (a storage image).
    pub fn decls(width: u32, height: u32) -> [ResourceDecl; 7] {
        let more = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let target =
            |name, format| ResourceDecl::attachment(name, format, width, height, 1).usage(more);
        [
            target("position", GBUFFER_FORMAT),
            target("normal", GBUFFER_FORMAT),
            target("albedo", GBUFFER_FORMAT),
            target("velocity", VELOCITY_FORMAT),
            target("ids", ID_FORMAT),
            target("depth", DEPTH_FORMAT),
            ResourceDecl::image("color", COLOR_FORMAT, width, height),
        ]
    }

    pub fn new(gpu: &cbr_gpu::Gpu, prefix: &str, width: u32, height: u32) -> Result<GBuffer> {
        let [position, normal, albedo, velocity, ids, depth, color] = GBuffer::decls(width, height);
        Ok(GBuffer {
            position: position.make_image(gpu, prefix)?,
            normal: normal.make_image(gpu, prefix)?,
            albedo: albedo.make_image(gpu, prefix)?,
            velocity: velocity.make_image(gpu, prefix)?,
            ids: ids.make_image(gpu, prefix)?,
            depth: depth.make_image(gpu, prefix)?,
            color: color.make_image(gpu, prefix)?,
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

    /// Bytes of its images at `width` x `height` (from [`GBuffer::decls`]).
    pub fn bytes(width: u32, height: u32) -> u64 {
        crate::pass::estimate(&GBuffer::decls(width, height), "g").total()
    }
}
