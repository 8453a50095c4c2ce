//! A command buffer being recorded. Every image/buffer use goes through `use_image`/`use_buffer`,
//! which emits the barrier derived from the resource's previous declared access.

use ash::vk;

use crate::access::{Access, image_barrier, memory_barrier};
use crate::context::Gpu;
use crate::pipeline::{DescriptorSet, Pipeline};
use crate::query::Traffic;
use crate::resource::{Buffer, Image, Readback, is_depth_format};

pub struct Cmd {
    gpu: Gpu,
    pub(crate) cb: vk::CommandBuffer,
    /// Descriptor sets made while recording (one per dispatch of a declared pass): kept until
    /// the submission has completed, then handed to the deletion queue.
    sets: Vec<DescriptorSet>,
    /// What was recorded since the last [`Cmd::take_traffic`] declared it moves (the profiler
    /// takes it per scope).
    traffic: Traffic,
}

/// One attachment of a rendering pass; `clear: None` loads the previous contents.
pub struct Attachment<'a> {
    pub image: &'a Image,
    pub clear: Option<vk::ClearValue>,
}

/// One buffer-to-image copy of a mip level.
pub struct LevelCopy {
    pub buffer_offset: u64,
    pub level: u32,
    pub width: u32,
    pub height: u32,
}

impl Cmd {
    pub(crate) fn new(gpu: Gpu, cb: vk::CommandBuffer) -> Cmd {
        Cmd {
            gpu,
            cb,
            sets: Vec::new(),
            traffic: Traffic::default(),
        }
    }

    /// Adds to what the recording declares it moves ([`Traffic`]).
    pub fn add_traffic(&mut self, t: &Traffic) {
        self.traffic.add(t);
    }

    /// What was declared since the last call.
    pub fn take_traffic(&mut self) -> Traffic {
        std::mem::take(&mut self.traffic)
    }

    /// Keeps `set` alive until this command buffer's submission has completed.
    pub fn keep(&mut self, set: DescriptorSet) {
        self.sets.push(set);
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    fn dev(&self) -> &ash::Device {
        &self.gpu.inner.device
    }

    /// Declares the next use of `image`; records the barrier from its previous use if one is needed.
    pub fn use_image(&mut self, image: &Image, access: Access) {
        let from = image.last.get();
        if let Some(b) = image_barrier(image.raw(), image.aspect(), from, access) {
            // A depth image rendered with custom sample locations is transitioned with them
            // (VK_EXT_sample_locations), so its contents are interpreted as they were written.
            let locations = image
                .sample_locations
                .get()
                .map(|l| l.map(|[x, y]| vk::SampleLocationEXT { x, y }));
            let mut info = locations.as_ref().map(|l| {
                vk::SampleLocationsInfoEXT::default()
                    .sample_locations_per_pixel(vk::SampleCountFlags::TYPE_2)
                    .sample_location_grid_size(vk::Extent2D {
                        width: 1,
                        height: 1,
                    })
                    .sample_locations(l)
            });
            let b = match info.as_mut() {
                Some(i) => b.push_next(i),
                None => b,
            };
            let bs = [b];
            let dep = vk::DependencyInfo::default().image_memory_barriers(&bs);
            // SAFETY: recording state; the image belongs to this device; the chained sample
            // locations outlive the call.
            unsafe { self.dev().cmd_pipeline_barrier2(self.cb, &dep) };
        }
        image.last.set(access);
    }

    /// Sets the 2-sample locations for the following draws (dynamic state of pipelines built
    /// with `GraphicsDesc::sample_locations`) and records them on `depth`, whose later layout
    /// transitions carry them. Does nothing without VK_EXT_sample_locations (callers check
    /// `Caps::sample_locations_2x` first).
    pub fn set_sample_locations(&mut self, depth: &Image, locations: [[f32; 2]; 2]) {
        let Some(ext) = self.gpu.inner.sample_locations.as_ref() else {
            return;
        };
        let l = locations.map(|[x, y]| vk::SampleLocationEXT { x, y });
        let info = vk::SampleLocationsInfoEXT::default()
            .sample_locations_per_pixel(vk::SampleCountFlags::TYPE_2)
            .sample_location_grid_size(vk::Extent2D {
                width: 1,
                height: 1,
            })
            .sample_locations(&l);
        // SAFETY: recording state; the bound pipeline has SAMPLE_LOCATIONS_EXT dynamic.
        unsafe { ext.cmd_set_sample_locations(self.cb, &info) };
        depth.sample_locations.set(Some(locations));
    }

    /// Declares the next use of `buffer`; records a memory barrier if one is needed.
    pub fn use_buffer(&mut self, buffer: &Buffer, access: Access) {
        let from = buffer.last.get();
        if let Some(b) = memory_barrier(from, access) {
            let bs = [b];
            let dep = vk::DependencyInfo::default().memory_barriers(&bs);
            // SAFETY: recording state.
            unsafe { self.dev().cmd_pipeline_barrier2(self.cb, &dep) };
        }
        buffer.last.set(access);
    }

    /// An execution + memory barrier between everything before and everything after.
    pub fn full_barrier(&mut self) {
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        let dep = vk::DependencyInfo::default().memory_barriers(&b);
        // SAFETY: recording state.
        unsafe { self.dev().cmd_pipeline_barrier2(self.cb, &dep) };
    }

    /// Fills the whole of `buffer` with the 32-bit `value` (vkCmdFillBuffer): clearing per-pixel
    /// heads and counters.
    pub fn fill_buffer(&mut self, buffer: &Buffer, value: u32) {
        self.use_buffer(buffer, Access::TransferDst);
        // SAFETY: recording state; the whole buffer, its size a multiple of 4 (Buffer::new).
        unsafe {
            self.dev()
                .cmd_fill_buffer(self.cb, buffer.raw(), 0, vk::WHOLE_SIZE, value)
        };
    }

    /// Writes `data` at the start of `buffer` (vkCmdUpdateBuffer: at most 65536 bytes, recorded
    /// into the command buffer): small per-frame parameters such as an indirect dispatch's.
    pub fn update_buffer(&mut self, buffer: &Buffer, data: &[u32]) {
        assert!(
            !data.is_empty() && data.len() * 4 <= 65536 && data.len() as u64 * 4 <= buffer.size(),
            "vkCmdUpdateBuffer takes 4 to 65536 bytes within the buffer ({} bytes), not {}",
            buffer.size(),
            data.len() * 4
        );
        self.use_buffer(buffer, Access::TransferDst);
        // SAFETY: recording state; the data is 4 to 65536 bytes, a multiple of 4, and within the
        // buffer (asserted above).
        unsafe {
            self.dev()
                .cmd_update_buffer(self.cb, buffer.raw(), 0, bytemuck::cast_slice(data))
        };
    }

    pub fn copy_buffer(&mut self, src: &Buffer, dst: &Buffer, size: u64) {
        self.use_buffer(src, Access::TransferSrc);
        self.use_buffer(dst, Access::TransferDst);
        let r = [vk::BufferCopy::default().size(size)];
        // SAFETY: both buffers are at least `size` bytes (callers size them from the same data).
        unsafe {
            self.dev()
                .cmd_copy_buffer(self.cb, src.raw(), dst.raw(), &r)
        };
    }

    /// Copies mip levels from a staging buffer into `image`, leaving it ready for sampling.
    pub fn upload_levels(
        &mut self,
        src: &Buffer,
        image: &Image,
        levels: &[LevelCopy],
        then: Access,
    ) {
        self.use_buffer(src, Access::TransferSrc);
        self.use_image(image, Access::TransferDst);
        let regions: Vec<vk::BufferImageCopy> = levels
            .iter()
            .map(|l| {
                vk::BufferImageCopy::default()
                    .buffer_offset(l.buffer_offset)
                    .image_subresource(
                        vk::ImageSubresourceLayers::default()
                            .aspect_mask(image.aspect())
                            .mip_level(l.level)
                            .layer_count(1),
                    )
                    .image_extent(vk::Extent3D {
                        width: l.width,
                        height: l.height,
                        depth: 1,
                    })
            })
            .collect();
        // SAFETY: regions lie inside both resources (computed from the same mip chain).
        unsafe {
            self.dev().cmd_copy_buffer_to_image(
                self.cb,
                src.raw(),
                image.raw(),
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
        self.use_image(image, then);
    }

    /// Copies level 0 (all layers) of `image` into `rb`, visible to the host after the submission.
    pub fn read_image(&mut self, image: &Image, rb: &Readback) {
        self.use_image(image, Access::TransferSrc);
        self.use_buffer(&rb.buffer, Access::TransferDst);
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(image.aspect())
                    .layer_count(image.layers),
            )
            .image_extent(vk::Extent3D {
                width: image.width,
                height: image.height,
                depth: 1,
            })];
        // SAFETY: the readback buffer was sized for this image.
        unsafe {
            self.dev().cmd_copy_image_to_buffer(
                self.cb,
                image.raw(),
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                rb.buffer.raw(),
                &region,
            )
        };
        self.use_buffer(&rb.buffer, Access::HostRead);
    }

    /// Copies the start of `buffer` into `rb` (as many bytes as `rb` holds), visible to the host
    /// after the submission.
    pub fn read_buffer(&mut self, buffer: &Buffer, rb: &Readback) {
        self.copy_buffer(buffer, &rb.buffer, rb.buffer.size());
        self.use_buffer(&rb.buffer, Access::HostRead);
    }

    /// Begins dynamic rendering into the given attachments over their full extent.
    pub fn begin_rendering(
        &mut self,
        colors: &[Attachment],
        depth: Option<Attachment>,
        layers: u32,
    ) {
        let mut extent = vk::Extent2D::default();
        // Attachments: written once; loaded ones (no clear) and the depth also read once.
        let mut t = Traffic {
            render_passes: 1,
            ..Traffic::default()
        };
        for a in colors.iter().chain(depth.as_ref()) {
            let b = a.image.traffic_bytes();
            t.bytes_written += b;
            if a.clear.is_none() || is_depth_format(a.image.format) {
                t.bytes_read += b;
            }
        }
        self.traffic.add(&t);
        let color_infos: Vec<vk::RenderingAttachmentInfo> = colors
            .iter()
            .map(|a| {
                self.use_image(a.image, Access::ColorAttachmentWrite);
                extent = a.image.extent();
                attachment_info(a, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            })
            .collect();
        let depth_info = depth.as_ref().map(|a| {
            self.use_image(a.image, Access::DepthAttachmentWrite);
            extent = a.image.extent();
            attachment_info(a, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        });
        let mut info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(layers)
            .color_attachments(&color_infos);
        if let Some(d) = depth_info.as_ref() {
            info = info.depth_attachment(d);
        }
        // SAFETY: attachments were transitioned above; formats match the pipelines used inside.
        unsafe { self.dev().cmd_begin_rendering(self.cb, &info) };
        self.set_viewport(0.0, 0.0, extent.width as f32, extent.height as f32);
    }

    pub fn end_rendering(&mut self) {
        // SAFETY: paired with `begin_rendering`.
        unsafe { self.dev().cmd_end_rendering(self.cb) };
    }

    /// Sets the viewport (sub-pixel offsets allowed) and a scissor covering it.
    pub fn set_viewport(&mut self, x: f32, y: f32, w: f32, h: f32) {
        let vp = [vk::Viewport {
            x,
            y,
            width: w,
            height: h,
            min_depth: 0.0,
            max_depth: 1.0,
        }];
        let sc = [vk::Rect2D {
            offset: vk::Offset2D {
                x: x.floor().max(0.0) as i32,
                y: y.floor().max(0.0) as i32,
            },
            extent: vk::Extent2D {
                width: w.ceil() as u32 + 1,
                height: h.ceil() as u32 + 1,
            },
        }];
        // SAFETY: recording state; pipelines declare viewport and scissor dynamic.
        unsafe {
            self.dev().cmd_set_viewport(self.cb, 0, &vp);
            self.dev().cmd_set_scissor(self.cb, 0, &sc);
        }
    }

    pub fn bind_pipeline(&mut self, p: &Pipeline) {
        // SAFETY: recording state.
        unsafe { self.dev().cmd_bind_pipeline(self.cb, p.bind_point, p.raw) };
    }

    pub fn bind_set(&mut self, p: &Pipeline, index: u32, set: &DescriptorSet) {
        // SAFETY: the set's layout is the pipeline's layout at `index` (checked when the set was made).
        unsafe {
            self.dev().cmd_bind_descriptor_sets(
                self.cb,
                p.bind_point,
                p.layout,
                index,
                &[set.raw],
                &[],
            )
        };
    }

    pub fn push_constants(&mut self, p: &Pipeline, data: &[u8]) {
        // SAFETY: the layout's push range covers `data` for all stages (asserted at pipeline creation).
        unsafe {
            self.dev()
                .cmd_push_constants(self.cb, p.layout, vk::ShaderStageFlags::ALL, 0, data)
        };
    }

    /// Binds u32 indices. Declare the buffer's use (`use_buffer(.., GraphicsRead)`) before the
    /// rendering pass begins: barriers are not allowed inside it.
    pub fn bind_index_buffer(&mut self, b: &Buffer) {
        // SAFETY: u32 indices.
        unsafe {
            self.dev()
                .cmd_bind_index_buffer(self.cb, b.raw(), 0, vk::IndexType::UINT32)
        };
    }

    pub fn draw_indexed(
        &mut self,
        index_count: u32,
        instances: u32,
        first_index: u32,
        first_instance: u32,
    ) {
        // SAFETY: recording state inside a rendering pass.
        unsafe {
            self.dev().cmd_draw_indexed(
                self.cb,
                index_count,
                instances,
                first_index,
                0,
                first_instance,
            )
        };
    }

    pub fn draw(&mut self, vertices: u32, instances: u32) {
        // SAFETY: recording state inside a rendering pass.
        unsafe { self.dev().cmd_draw(self.cb, vertices, instances, 0, 0) };
    }

    pub fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        // SAFETY: recording state with a compute pipeline bound.
        unsafe { self.dev().cmd_dispatch(self.cb, x, y, z) };
    }

    /// A dispatch whose group counts (VkDispatchIndirectCommand: x, y, z) the GPU wrote into
    /// `buffer` at byte `offset` (a multiple of 4); the buffer needs INDIRECT_BUFFER usage and
    /// [`Access::ComputeIndirect`] declared before.
    pub fn dispatch_indirect(&mut self, buffer: &Buffer, offset: u64) {
        // SAFETY: recording state with a compute pipeline bound; the caller's buffer holds the
        // command at `offset`.
        unsafe {
            self.dev()
                .cmd_dispatch_indirect(self.cb, buffer.raw(), offset)
        };
    }
}

fn attachment_info<'a>(a: &Attachment, layout: vk::ImageLayout) -> vk::RenderingAttachmentInfo<'a> {
    let info = vk::RenderingAttachmentInfo::default()
        .image_view(a.image.view())
        .image_layout(layout)
        .store_op(vk::AttachmentStoreOp::STORE);
    match a.clear {
        Some(c) => info.load_op(vk::AttachmentLoadOp::CLEAR).clear_value(c),
        None => info.load_op(vk::AttachmentLoadOp::LOAD),
    }
}
