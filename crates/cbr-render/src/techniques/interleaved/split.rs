//! `interleaved`'s three passes between the G-buffer and the lighting pass
//! (shaders/interleaved/): `interleaved.split` (the G-buffer into M x N sub-images),
//! `interleaved.shade` (sub-image k with VPL subset k) and `interleaved.gather` (the estimates back
//! to their pixels). One set layout and one set serve the three pipelines.

use bytemuck::{Pod, Zeroable};
use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Image, ImageDesc,
    PassKind, Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Write, vk,
};

use crate::targets::GBUFFER_FORMAT;
use crate::technique::BuildCtx;
use crate::techniques::deferred::GBuffer;

/// The passes' set: the one definition of its bindings.
pub const BINDINGS: [BindingDesc; 7] = {
    use DescriptorKind::{CombinedImageSampler as S, StorageBuffer as B, StorageImage as I};
    [
        BindingDesc::one("position", 0, S),
        BindingDesc::one("normal", 1, S),
        BindingDesc::one("vpls", 2, B),
        BindingDesc::one("split_position", 3, I),
        BindingDesc::one("split_normal", 4, I),
        BindingDesc::one("split_irradiance", 5, I),
        BindingDesc::one("irradiance", 6, I),
    ]
};

/// Push constants (interleave.glsl's `Push`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SplitPush {
    /// W, H, Ws, Hs.
    pub size: [i32; 4],
    /// x: VPLs.
    pub counts: [u32; 4],
    /// x: the VPL clamp c (m^2).
    pub params: [f32; 4],
}

/// The sub-images' side for a W x H frame split M x N: ceil(W/M) x ceil(H/N).
pub fn sub_image(width: u32, height: u32, m: u32, n: u32) -> (u32, u32) {
    (width.div_ceil(m), height.div_ceil(n))
}

pub struct SplitPasses {
    split: Pipeline,
    shade: Pipeline,
    gather: Pipeline,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
    split_position: Image,
    split_normal: Image,
    split_irradiance: Image,
    /// The gathered estimates at full resolution (RGBA32F), read by the lighting pass.
    pub irradiance: Image,
    tile: (u32, u32),
    size: [i32; 4],
}

impl SplitPasses {
    pub fn new(
        ctx: &BuildCtx,
        g: &GBuffer,
        vpls: &Buffer,
        (m, n): (u32, u32),
    ) -> Result<SplitPasses> {
        let gpu = ctx.gpu;
        let layout = SetLayout::new(gpu, "interleaved.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("TILE_M".into(), m.to_string()));
        defines.push(("TILE_N".into(), n.to_string()));
        let pipeline = |name: &str, file: &str| {
            let cs = ctx.shaders.compile(file, &defines)?;
            Pipeline::compute(
                gpu,
                &ComputeDesc {
                    name,
                    shader: &cs,
                    set_layouts: &[&layout],
                    push_constant_bytes: std::mem::size_of::<SplitPush>() as u32,
                },
            )
        };
        let split = pipeline("interleaved.split", "interleaved/split.comp")?;
        let shade = pipeline("interleaved.shade", "interleaved/shade.comp")?;
        let gather = pipeline("interleaved.gather", "interleaved/gather.comp")?;
        let (w, h) = (ctx.width, ctx.height);
        let (ws, hs) = sub_image(w, h, m, n);
        let img = |name: &str, width, height, usage| {
            let name = format!("interleaved.{name}");
            let d = ImageDesc::new_2d(&name, GBUFFER_FORMAT, width, height, usage);
            Image::new(gpu, &d)
        };
        let storage = vk::ImageUsageFlags::STORAGE;
        let split_position = img("split_position", m * ws, n * hs, storage)?;
        let split_normal = img("split_normal", m * ws, n * hs, storage)?;
        let split_irradiance = img("split_irradiance", m * ws, n * hs, storage)?;
        let irradiance = img("irradiance", w, h, storage | vk::ImageUsageFlags::SAMPLED)?;
        let sampler = Sampler::new(gpu, "interleaved.sampler", SamplerDesc::NEAREST)?;
        let set = DescriptorSet::new(
            gpu,
            "interleaved.set",
            &layout,
            &[
                Write::Sampled(0, vec![(&g.position, &sampler)]),
                Write::Sampled(1, vec![(&g.normal, &sampler)]),
                Write::Buffer(2, vpls),
                Write::Storage(3, &split_position),
                Write::Storage(4, &split_normal),
                Write::Storage(5, &split_irradiance),
                Write::Storage(6, &irradiance),
            ],
        )?;
        Ok(SplitPasses {
            split,
            shade,
            gather,
            _layout: layout,
            set,
            _sampler: sampler,
            split_position,
            split_normal,
            split_irradiance,
            irradiance,
            tile: (m, n),
            size: [w as i32, h as i32, ws as i32, hs as i32],
        })
    }

    /// Bytes of the split images and the gathered estimates.
    pub fn bytes(&self) -> u64 {
        let (m, n) = self.tile;
        let split = u64::from(m) * self.size[2] as u64 * u64::from(n) * self.size[3] as u64;
        (3 * split + self.size[0] as u64 * self.size[1] as u64) * 16
    }

    /// Split, shade (with `count` VPLs, clamp `clamp_d2`) and gather.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        g: &GBuffer,
        vpls: &Buffer,
        count: u32,
        clamp_d2: f32,
    ) {
        let push = SplitPush {
            size: self.size,
            counts: [count, 0, 0, 0],
            params: [clamp_d2, 0.0, 0.0, 0.0],
        };
        let (m, n) = self.tile;
        let split_groups = (
            (m * self.size[2] as u32).div_ceil(8),
            (n * self.size[3] as u32).div_ceil(8),
        );
        // Split: G-buffer -> sub-images.
        cmd.use_image(&g.position, Access::ComputeSampled);
        cmd.use_image(&g.normal, Access::ComputeSampled);
        cmd.use_image(&self.split_position, Access::ComputeStorageWrite);
        cmd.use_image(&self.split_normal, Access::ComputeStorageWrite);
        self.dispatch(
            cmd,
            profiler,
            &self.split,
            "interleaved.split",
            &push,
            split_groups,
        );
        // Shade: sub-image k with subset k.
        cmd.use_image(&self.split_position, Access::ComputeStorageReadWrite);
        cmd.use_image(&self.split_normal, Access::ComputeStorageReadWrite);
        cmd.use_image(&self.split_irradiance, Access::ComputeStorageWrite);
        cmd.use_buffer(vpls, Access::ComputeSampled);
        self.dispatch(
            cmd,
            profiler,
            &self.shade,
            "interleaved.shade",
            &push,
            split_groups,
        );
        // Gather: sub-images -> pixels.
        cmd.use_image(&self.split_irradiance, Access::ComputeStorageReadWrite);
        cmd.use_image(&self.irradiance, Access::ComputeStorageWrite);
        let full = (
            (self.size[0] as u32).div_ceil(8),
            (self.size[1] as u32).div_ceil(8),
        );
        self.dispatch(
            cmd,
            profiler,
            &self.gather,
            "interleaved.gather",
            &push,
            full,
        );
    }

    fn dispatch(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        pipeline: &Pipeline,
        name: &str,
        push: &SplitPush,
        (x, y): (u32, u32),
    ) {
        let scope = profiler.begin(cmd, name, PassKind::Compute);
        cmd.bind_pipeline(pipeline);
        cmd.bind_set(pipeline, 0, &self.set);
        cmd.push_constants(pipeline, bytemuck::bytes_of(push));
        cmd.dispatch(x, y, 1);
        profiler.end(cmd, scope);
    }
}
