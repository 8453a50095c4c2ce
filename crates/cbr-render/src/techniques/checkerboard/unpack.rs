//! The checkerboard technique's own passes: the layouts' raster targets, and `unpack`, which
//! rebuilds the full-resolution checkerboard frame through shaders/inc/layout_fetch.glsl
//! (`--resolve none`; the resolve of the next issue reads the same include).

use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, Location,
    PassKind, Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Shaders, Write, vk,
};

use crate::layouts::LayoutPlan;
use crate::memory::MemoryEstimate;
use crate::scene_pass::layout_id;
use crate::targets::FrameTargets;

pub const UNPACK_BINDINGS: [BindingDesc; 5] = [
    BindingDesc::one("color", 0, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("velocity", 1, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("ids", 2, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("depth", 3, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("out", 4, DescriptorKind::StorageBuffer),
];

/// One unpacked pixel, as `Pixel` in shaders/checkerboard/unpack.comp (std430: 48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct UnpackedPixel {
    pub color: [f32; 4],
    /// Velocity x, y; reverse-Z depth; 1 when shaded this frame.
    pub velocity_depth_mask: [f32; 4],
    pub ids: [u32; 4],
}

pub struct UnpackPass {
    pipeline: Pipeline,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
    /// Host-visible result, one `UnpackedPixel` per full-res pixel.
    pub out: Buffer,
    width: u32,
    height: u32,
}

impl UnpackPass {
    /// What [`UnpackPass::new`] allocates: one host-visible `UnpackedPixel` per full-resolution
    /// pixel, bound as a storage buffer.
    pub fn estimate(e: &mut MemoryEstimate, plan: &LayoutPlan) {
        let bytes = u64::from(plan.width)
            * u64::from(plan.height)
            * std::mem::size_of::<UnpackedPixel>() as u64;
        e.storage_buffer("unpack.out", bytes, true);
    }

    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        plan: &LayoutPlan,
        targets: &FrameTargets,
    ) -> Result<UnpackPass> {
        let layout = SetLayout::new(gpu, "unpack.set_layout", &UNPACK_BINDINGS)?;
        let mut defines: Vec<(String, String)> =
            UNPACK_BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("LAYOUT".into(), layout_id(plan.layout).to_string()));
        defines.push((
            "MSAA_LOCATIONS".into(),
            u32::from(plan.sample_locations.is_some()).to_string(),
        ));
        let cs = shaders.compile("checkerboard/unpack.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "checkerboard.unpack",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: 16,
            },
        )?;
        let sampler = Sampler::new(gpu, "unpack.sampler", SamplerDesc::NEAREST)?;
        let bytes = u64::from(plan.width)
            * u64::from(plan.height)
            * std::mem::size_of::<UnpackedPixel>() as u64;
        let out = Buffer::new(
            gpu,
            "unpack.out",
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            Location::GpuToCpu,
        )?;
        let set = DescriptorSet::new(
            gpu,
            "unpack.set",
            &layout,
            &[
                Write::Sampled(0, vec![(&targets.color, &sampler)]),
                Write::Sampled(1, vec![(&targets.velocity, &sampler)]),
                Write::Sampled(2, vec![(&targets.ids, &sampler)]),
                Write::Sampled(3, vec![(&targets.depth, &sampler)]),
                Write::Buffer(4, &out),
            ],
        )?;
        Ok(UnpackPass {
            pipeline,
            _layout: layout,
            set,
            _sampler: sampler,
            out,
            width: plan.width,
            height: plan.height,
        })
    }

    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        targets: &FrameTargets,
        plan: &LayoutPlan,
    ) {
        for img in [
            &targets.color,
            &targets.velocity,
            &targets.ids,
            &targets.depth,
        ] {
            cmd.use_image(img, Access::ComputeSampled);
        }
        cmd.use_buffer(&self.out, Access::ComputeStorageWrite);
        let scope = profiler.begin(cmd, "checkerboard.unpack", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        let push = [
            self.width as i32,
            self.height as i32,
            plan.parity as i32,
            plan.tangram as i32,
        ];
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
        cmd.dispatch(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        profiler.end(cmd, scope);
        cmd.use_buffer(&self.out, Access::HostRead);
    }
}
