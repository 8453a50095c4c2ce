//! Declared accesses and the one helper that turns a pair of them into a barrier.
//! Passes say how they use a resource; they never pick stage or access masks by hand.

use ash::vk;

/// How a command uses an image or buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Contents do not matter (first use, or being overwritten whole).
    Undefined,
    ColorAttachmentWrite,
    DepthAttachmentWrite,
    /// Sampled / read in a fragment shader.
    FragmentSampled,
    /// Sampled / read in a compute shader.
    ComputeSampled,
    ComputeStorageWrite,
    ComputeStorageReadWrite,
    /// Storage image or buffer read (not written) in a compute shader.
    ComputeStorageRead,
    /// Uniform buffer read in a compute shader (buffers).
    ComputeUniformRead,
    TransferSrc,
    TransferDst,
    /// Read by the host after the submission completes (buffers).
    HostRead,
    /// Vertex/index/uniform/storage reads by the graphics pipeline (buffers).
    GraphicsRead,
    /// Storage writes (atomics) from fragment shaders (buffers).
    FragmentStorageWrite,
    /// Read by a compute shader and as the parameters of an indirect dispatch (buffers).
    ComputeIndirect,
}

impl Access {
    pub fn stage(self) -> vk::PipelineStageFlags2 {
        use vk::PipelineStageFlags2 as S;
        match self {
            Access::Undefined => S::NONE,
            Access::ColorAttachmentWrite => S::COLOR_ATTACHMENT_OUTPUT,
            Access::DepthAttachmentWrite => S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            Access::FragmentSampled => S::FRAGMENT_SHADER,
            Access::ComputeSampled
            | Access::ComputeStorageWrite
            | Access::ComputeStorageReadWrite
            | Access::ComputeStorageRead
            | Access::ComputeUniformRead => S::COMPUTE_SHADER,
            Access::TransferSrc | Access::TransferDst => S::COPY | S::BLIT | S::CLEAR,
            Access::HostRead => S::HOST,
            Access::GraphicsRead => {
                S::VERTEX_INPUT | S::VERTEX_SHADER | S::FRAGMENT_SHADER | S::GEOMETRY_SHADER
            }
            Access::FragmentStorageWrite => S::FRAGMENT_SHADER,
            Access::ComputeIndirect => S::DRAW_INDIRECT | S::COMPUTE_SHADER,
        }
    }

    pub fn access(self) -> vk::AccessFlags2 {
        use vk::AccessFlags2 as A;
        match self {
            Access::Undefined => A::NONE,
            Access::ColorAttachmentWrite => A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
            Access::DepthAttachmentWrite => {
                A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ
            }
            Access::FragmentSampled | Access::ComputeSampled => {
                A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ
            }
            Access::ComputeStorageWrite => A::SHADER_STORAGE_WRITE,
            Access::ComputeStorageReadWrite => A::SHADER_STORAGE_WRITE | A::SHADER_STORAGE_READ,
            Access::ComputeStorageRead => A::SHADER_STORAGE_READ,
            Access::ComputeUniformRead => A::UNIFORM_READ,
            Access::TransferSrc => A::TRANSFER_READ,
            Access::TransferDst => A::TRANSFER_WRITE,
            Access::HostRead => A::HOST_READ,
            Access::GraphicsRead => {
                A::VERTEX_ATTRIBUTE_READ
                    | A::INDEX_READ
                    | A::UNIFORM_READ
                    | A::SHADER_STORAGE_READ
                    | A::SHADER_SAMPLED_READ
            }
            Access::FragmentStorageWrite => A::SHADER_STORAGE_WRITE | A::SHADER_STORAGE_READ,
            Access::ComputeIndirect => A::INDIRECT_COMMAND_READ | A::SHADER_STORAGE_READ,
        }
    }

    /// The image layout this access needs.
    pub fn layout(self, depth: bool) -> vk::ImageLayout {
        use vk::ImageLayout as L;
        match self {
            Access::Undefined => L::UNDEFINED,
            Access::ColorAttachmentWrite => L::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthAttachmentWrite => L::DEPTH_ATTACHMENT_OPTIMAL,
            Access::FragmentSampled | Access::ComputeSampled if depth => L::DEPTH_READ_ONLY_OPTIMAL,
            Access::FragmentSampled | Access::ComputeSampled => L::SHADER_READ_ONLY_OPTIMAL,
            Access::ComputeStorageWrite
            | Access::ComputeStorageReadWrite
            | Access::ComputeStorageRead
            | Access::ComputeUniformRead => L::GENERAL,
            Access::TransferSrc => L::TRANSFER_SRC_OPTIMAL,
            Access::TransferDst => L::TRANSFER_DST_OPTIMAL,
            Access::HostRead
            | Access::GraphicsRead
            | Access::FragmentStorageWrite
            | Access::ComputeIndirect => L::GENERAL,
        }
    }

    pub fn is_write(self) -> bool {
        matches!(
            self,
            Access::ColorAttachmentWrite
                | Access::DepthAttachmentWrite
                | Access::ComputeStorageWrite
                | Access::ComputeStorageReadWrite
                | Access::TransferDst
                | Access::FragmentStorageWrite
        )
    }
}

/// The barrier between two accesses of one image, or `None` when none is needed (read after read
/// in the same layout).
pub fn image_barrier(
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    from: Access,
    to: Access,
) -> Option<vk::ImageMemoryBarrier2<'static>> {
    let depth = aspect.contains(vk::ImageAspectFlags::DEPTH);
    let (old, new) = (from.layout(depth), to.layout(depth));
    if old == new && !from.is_write() && !to.is_write() && from != Access::Undefined {
        return None;
    }
    Some(
        vk::ImageMemoryBarrier2::default()
            .image(image)
            .src_stage_mask(from.stage())
            .src_access_mask(if from.is_write() {
                from.access()
            } else {
                vk::AccessFlags2::NONE
            })
            .dst_stage_mask(to.stage())
            .dst_access_mask(to.access())
            .old_layout(old)
            .new_layout(new)
            .subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(aspect)
                    .level_count(vk::REMAINING_MIP_LEVELS)
                    .layer_count(vk::REMAINING_ARRAY_LAYERS),
            ),
    )
}

/// The memory barrier between two accesses of a buffer, or `None` for read after read.
pub fn memory_barrier(from: Access, to: Access) -> Option<vk::MemoryBarrier2<'static>> {
    if !from.is_write() && !to.is_write() {
        return None;
    }
    Some(
        vk::MemoryBarrier2::default()
            .src_stage_mask(from.stage())
            .src_access_mask(if from.is_write() {
                from.access()
            } else {
                vk::AccessFlags2::NONE
            })
            .dst_stage_mask(to.stage())
            .dst_access_mask(to.access()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_after_read_needs_no_barrier() {
        let img = vk::Image::null();
        let c = vk::ImageAspectFlags::COLOR;
        assert!(image_barrier(img, c, Access::FragmentSampled, Access::FragmentSampled).is_none());
        assert!(memory_barrier(Access::GraphicsRead, Access::HostRead).is_none());
    }

    #[test]
    fn write_then_read_transitions_layout_and_makes_writes_visible() {
        let b = image_barrier(
            vk::Image::null(),
            vk::ImageAspectFlags::COLOR,
            Access::ColorAttachmentWrite,
            Access::TransferSrc,
        )
        .expect("barrier");
        assert_eq!(b.old_layout, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        assert_eq!(b.new_layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        assert!(
            b.src_access_mask
                .contains(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
        );
        assert!(b.dst_access_mask.contains(vk::AccessFlags2::TRANSFER_READ));
        let d = image_barrier(
            vk::Image::null(),
            vk::ImageAspectFlags::DEPTH,
            Access::DepthAttachmentWrite,
            Access::ComputeSampled,
        )
        .expect("barrier");
        assert_eq!(d.new_layout, vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL);
    }

    #[test]
    fn first_use_is_a_transition_from_undefined() {
        let b = image_barrier(
            vk::Image::null(),
            vk::ImageAspectFlags::COLOR,
            Access::Undefined,
            Access::ColorAttachmentWrite,
        )
        .expect("barrier");
        assert_eq!(b.old_layout, vk::ImageLayout::UNDEFINED);
        assert_eq!(b.src_access_mask, vk::AccessFlags2::NONE);
    }
}
