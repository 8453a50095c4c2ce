//! The per-frame outputs of a scene raster pass, and their formats (one place).

use cbr_gpu::{Gpu, Image, Result, vk};

use crate::memory::MemoryEstimate;
use crate::pass::ResourceDecl;

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

    /// The four targets' declarations: `layers` array layers and `samples` samples each
    /// (checkerboard layouts); `sample_locations`: a depth target compatible with custom sample
    /// locations (msaa2x with VK_EXT_sample_locations). TRANSFER_DST: tests upload synthetic
    /// samples (the resolve's CPU-reference test).
    pub fn decls(
        width: u32,
        height: u32,
        layers: u32,
        samples: u32,
        sample_locations: bool,
    ) -> [ResourceDecl; 4] {
        let more = vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::SAMPLED;
        let target = |name, format| {
            ResourceDecl::attachment(name, format, width, height, samples)
                .usage(more)
                .layers(layers)
        };
        let mut depth = target("depth", DEPTH_FORMAT);
        if sample_locations {
            depth = depth.flags(vk::ImageCreateFlags::SAMPLE_LOCATIONS_COMPATIBLE_DEPTH_EXT);
        }
        [
            target("color", COLOR_FORMAT),
            target("velocity", VELOCITY_FORMAT),
            target("ids", ID_FORMAT),
            depth,
        ]
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
        let decls = FrameTargets::decls(width, height, layers, samples, false);
        e.append(crate::pass::estimate(&decls, prefix));
    }

    /// Single-layer, single-sample targets (the native technique).
    pub fn new(gpu: &Gpu, prefix: &str, width: u32, height: u32) -> Result<FrameTargets> {
        FrameTargets::layered(gpu, prefix, width, height, 1, 1, false)
    }

    /// The targets of [`FrameTargets::decls`].
    pub fn layered(
        gpu: &Gpu,
        prefix: &str,
        width: u32,
        height: u32,
        layers: u32,
        samples: u32,
        sample_locations: bool,
    ) -> Result<FrameTargets> {
        let [color, velocity, ids, depth] =
            FrameTargets::decls(width, height, layers, samples, sample_locations);
        Ok(FrameTargets {
            color: color.make_image(gpu, prefix)?,
            velocity: velocity.make_image(gpu, prefix)?,
            ids: ids.make_image(gpu, prefix)?,
            depth: depth.make_image(gpu, prefix)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pass::ResourceKind;

    /// msaa2x's support is decided (cbr_gpu::Caps::integer_color_sample_counts) from the
    /// per-format answers for `INTEGER_ATTACHMENTS`: every integer target the frame declares
    /// must be there, with every usage it declares.
    #[test]
    fn integer_targets_are_the_ones_caps_asks_about() {
        let mut integer = 0;
        for sample_locations in [false, true] {
            for d in FrameTargets::decls(64, 36, 1, 2, sample_locations) {
                let ResourceKind::Image { format, usage, .. } = d.kind else {
                    panic!("{}: not an image", d.name);
                };
                let f = format!("{format:?}");
                if !(f.ends_with("_UINT") || f.ends_with("_SINT")) {
                    continue;
                }
                integer += 1;
                assert!(
                    cbr_gpu::caps::INTEGER_ATTACHMENTS
                        .iter()
                        .any(|&(af, au)| af == format && au.contains(usage)),
                    "{}: {f} with {usage:?} is not in INTEGER_ATTACHMENTS",
                    d.name
                );
            }
        }
        assert_eq!(
            integer, 2,
            "the ID target, with and without sample locations"
        );
    }
}
