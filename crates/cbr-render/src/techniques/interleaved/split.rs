//! `interleaved`'s passes between the G-buffer and the lighting pass (shaders/interleaved/):
//! `interleaved.split` (the G-buffer into M x N sub-images), `interleaved.shade` (sub-image k with
//! VPL subset k) and `interleaved.gather` (the estimates back to their pixels); with `implicit`
//! the one pass `interleaved.implicit` instead (each pixel its own position's subset, no split);
//! with `seed` the seed's blur, `interleaved.seed_blur_h` and `interleaved.seed_blur_v`; with
//! `floor` a copy kernel moving the split and gather passes' bytes (`interleaved.copy_floor`).
//! One set layout and one set serve every pipeline.

use bytemuck::{Pod, Zeroable};
use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Image, ImageDesc,
    Location, PassKind, Pipeline, Profiler, Readback, Result, Sampler, SamplerDesc, SetLayout,
    Write, vk,
};

use super::{Filter, InterleavedConfig};
use crate::memory::MemoryEstimate;
use crate::resolve::CopyFloor;
use crate::targets::GBUFFER_FORMAT;
use crate::technique::BuildCtx;
use crate::techniques::deferred::GBuffer;
use crate::techniques::deferred::lighting::LightSources;

/// The passes' set: the one definition of its bindings.
pub const BINDINGS: [BindingDesc; 15] = {
    use DescriptorKind::{CombinedImageSampler as S, StorageBuffer as B, StorageImage as I};
    [
        BindingDesc::one("position", 0, S),
        BindingDesc::one("normal", 1, S),
        BindingDesc::one("vpls", 2, B),
        BindingDesc::one("split_position", 3, B),
        BindingDesc::one("split_normal", 4, B),
        BindingDesc::one("split_irradiance", 5, B),
        BindingDesc::one("irradiance", 6, I),
        // `seed` only: the horizontal blur's output and the vertical's.
        BindingDesc::one("seed_tmp", 7, I),
        BindingDesc::one("seed_out", 8, I),
        // `direct` only: the scene's lights and the extra point lights, the specular estimates
        // (the mosaic's, the gathered ones, the seed's blur's two).
        BindingDesc::one("lights", 9, B),
        BindingDesc::one("points", 10, B),
        BindingDesc::one("split_specular", 11, B),
        BindingDesc::one("specular", 12, I),
        BindingDesc::one("seed_tmp_specular", 13, I),
        BindingDesc::one("seed_out_specular", 14, I),
    ]
};

/// Push constants (interleave.glsl's `Push`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SplitPush {
    /// W, H, Ws, Hs.
    pub size: [i32; 4],
    /// x: VPLs; with `direct`: y the scene's directional lights, z its point lights, w the
    /// extra point lights (`points=N`).
    pub counts: [u32; 4],
    /// x: the VPL clamp c (m^2).
    pub params: [f32; 4],
}

/// The sub-images' side for a W x H frame split M x N: ceil(W/M) x ceil(H/N).
pub fn sub_image(width: u32, height: u32, m: u32, n: u32) -> (u32, u32) {
    (width.div_ceil(m), height.div_ceil(n))
}

/// Bytes the split and gather passes move at least for a W x H frame: the split reads and writes
/// each pixel's position and normal (RGBA32F each), the gather reads and writes each pixel's
/// estimate (RGBA32F). Their copy kernel (`floor`) moves as many.
pub fn moved_bytes(width: u32, height: u32) -> (u64, u64) {
    let px = u64::from(width) * u64::from(height);
    (px * 48, px * 48)
}

/// Bytes of one texel of the split mosaic (a vec4 of f32).
const MOSAIC_WORD: u64 = 16;

/// The buffers of the `floor` copy kernel.
const FLOOR: &str = "interleaved.copy_floor";

/// `interleaved`'s storage: the split mosaic in storage buffers, one vec4 of f32 per texel, rows
/// one after another (absent with `implicit`); the full-resolution estimates in storage images
/// (the seed's blur ones present with `seed` only). The mosaic is only read and written in
/// runs (split.comp, gather.comp), where on llvmpipe a buffer word costs a fraction of an image
/// texel; the lighting pass's filter reads the estimates at data-dependent pixels, where
/// llvmpipe's texel fetches are faster (docs/interleaved.md, split and gather).
struct Storage {
    split_position: Option<Buffer>,
    split_normal: Option<Buffer>,
    irradiance: Estimate,
    /// `direct`: the point lights' specular estimates beside the irradiance.
    specular: Option<Estimate>,
}

/// One estimate through the passes: the shade pass's split mosaic (absent with `implicit`), the
/// gathered full-resolution image, and with `seed` its blur's two images (horizontal, vertical).
struct Estimate {
    split: Option<Buffer>,
    gathered: Image,
    seed: Option<(Image, Image)>,
}

impl Estimate {
    /// What the lighting pass filters: the gathered image, or with `seed` its blur.
    fn output(&self) -> &Image {
        match &self.seed {
            Some((_, out)) => out,
            None => &self.gathered,
        }
    }
}

pub struct SplitPasses {
    split: Option<(Pipeline, Pipeline, Pipeline)>,
    implicit: Option<Pipeline>,
    seed: Option<(Pipeline, Pipeline)>,
    floor: Option<CopyFloor>,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
    storage: Storage,
    /// `debug`: the split mosaic of the estimates, read back each frame.
    pub mosaic: Option<Readback>,
    tile: (u32, u32),
    size: [i32; 4],
}

impl SplitPasses {
    /// What [`SplitPasses::new`] allocates.
    pub fn estimate(e: &mut MemoryEstimate, config: &InterleavedConfig, w: u32, h: u32) {
        let (ws, hs) = sub_image(w, h, config.m, config.n);
        let (sw, sh) = (config.m * ws, config.n * hs);
        if !config.implicit {
            let bytes = u64::from(sw) * u64::from(sh) * MOSAIC_WORD;
            for name in ["split_position", "split_normal", "split_irradiance"] {
                e.storage_buffer(format!("interleaved.{name}"), bytes, false);
            }
            if config.direct {
                e.storage_buffer("interleaved.split_specular".to_string(), bytes, false);
            }
            if config.debug {
                e.buffer("readback.interleaved_mosaic", bytes, true);
            }
        }
        e.image("interleaved.irradiance", GBUFFER_FORMAT, w, h);
        if config.direct {
            e.image("interleaved.specular", GBUFFER_FORMAT, w, h);
        }
        if config.filter == Filter::Seed {
            e.image("interleaved.seed_tmp", GBUFFER_FORMAT, w, h);
            e.image("interleaved.seed_out", GBUFFER_FORMAT, w, h);
            if config.direct {
                e.image("interleaved.seed_tmp_specular", GBUFFER_FORMAT, w, h);
                e.image("interleaved.seed_out_specular", GBUFFER_FORMAT, w, h);
            }
        }
        if config.floor {
            CopyFloor::estimate(e, FLOOR, moved_bytes(w, h));
        }
    }

    pub fn new(
        ctx: &BuildCtx,
        g: &GBuffer,
        sources: &LightSources,
        config: &InterleavedConfig,
    ) -> Result<SplitPasses> {
        let vpls = sources.vpls;
        let gpu = ctx.gpu;
        let (m, n) = (config.m, config.n);
        let layout = SetLayout::new(gpu, "interleaved.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("TILE_M".into(), m.to_string()));
        defines.push(("TILE_N".into(), n.to_string()));
        if config.direct {
            defines.push(("DIRECT".into(), "1".into()));
        }
        let pipeline = |name: &str, file: &str, extra: &[&str]| {
            let mut d = defines.clone();
            d.extend(extra.iter().map(|k| (k.to_string(), "1".to_string())));
            let cs = ctx.shaders.compile(file, &d)?;
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
        // The gather (or implicit) pass's flags: DEBUG the round trip, SEED the seed's edges.
        let mut flags = Vec::new();
        if config.debug {
            flags.push("DEBUG");
        }
        if config.filter == Filter::Seed {
            flags.push("SEED");
        }
        let (split, implicit) = if config.implicit {
            let p = pipeline("interleaved.implicit", "interleaved/implicit.comp", &flags)?;
            (None, Some(p))
        } else {
            let split = pipeline("interleaved.split", "interleaved/split.comp", &[])?;
            let shade = pipeline("interleaved.shade", "interleaved/shade.comp", &[])?;
            // `box`: the gather sums each pixel's window row (the lighting pass's BOX_ROWS).
            if config.box_rows() {
                flags.push("BOX_ROWS");
            }
            let gather = pipeline("interleaved.gather", "interleaved/gather.comp", &flags)?;
            (Some((split, shade, gather)), None)
        };
        let seed = if config.filter == Filter::Seed {
            let file = "interleaved/seed_blur.comp";
            Some((
                pipeline("interleaved.seed_blur_h", file, &["HORIZONTAL"])?,
                pipeline("interleaved.seed_blur_v", file, &[])?,
            ))
        } else {
            None
        };
        let (w, h) = (ctx.width, ctx.height);
        let (ws, hs) = sub_image(w, h, m, n);
        let read_back = if config.debug {
            vk::BufferUsageFlags::TRANSFER_SRC
        } else {
            vk::BufferUsageFlags::empty()
        };
        let mosaic_bytes = u64::from(m * ws) * u64::from(n * hs) * MOSAIC_WORD;
        let buffer = |name: &str, bytes, usage| {
            let name = format!("interleaved.{name}");
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER | usage;
            Buffer::new(gpu, &name, bytes, usage, Location::GpuOnly)
        };
        let none = vk::BufferUsageFlags::empty();
        let split_buffer = |name: &str, usage| match config.implicit {
            true => Ok(None),
            false => buffer(name, mosaic_bytes, usage).map(Some),
        };
        let split_position = split_buffer("split_position", none)?;
        let split_normal = split_buffer("split_normal", none)?;
        let img = |name: &str, usage| {
            let name = format!("interleaved.{name}");
            Image::new(gpu, &ImageDesc::new_2d(&name, GBUFFER_FORMAT, w, h, usage))
        };
        let storage = vk::ImageUsageFlags::STORAGE;
        let sampled = storage | vk::ImageUsageFlags::SAMPLED;
        // An estimate's buffer and images: `split_NAME`, `NAME`, and `seed_tmp`, `seed_out` with
        // `suffix` (none for the irradiance, `_specular` for `direct`'s).
        let estimate = |name: &str, suffix: &str, usage| -> Result<Estimate> {
            Ok(Estimate {
                split: split_buffer(&format!("split_{name}"), usage)?,
                gathered: img(name, sampled)?,
                seed: match seed {
                    Some(_) => Some((
                        img(&format!("seed_tmp{suffix}"), storage)?,
                        img(&format!("seed_out{suffix}"), sampled)?,
                    )),
                    None => None,
                },
            })
        };
        let irradiance = estimate("irradiance", "", read_back)?;
        let specular = match config.direct {
            true => Some(estimate("specular", "_specular", none)?),
            false => None,
        };
        let mosaic = match (&irradiance.split, config.debug) {
            (Some(_), true) => Some(Readback::for_buffer(
                gpu,
                "readback.interleaved_mosaic",
                mosaic_bytes,
                m * ws,
                n * hs,
            )?),
            _ => None,
        };
        let floor = if config.floor {
            Some(CopyFloor::named(
                gpu,
                ctx.shaders,
                "interleaved.copy_floor",
                FLOOR,
                moved_bytes(w, h),
            )?)
        } else {
            None
        };
        let sampler = Sampler::new(gpu, "interleaved.sampler", SamplerDesc::NEAREST)?;
        // Bindings a mode does not use still hold a resource (lavapipe crashes binding a set
        // with an unwritten descriptor): images the gathered estimates, which every mode has;
        // buffers the VPLs (`implicit`'s mosaic, never accessed).
        fn or_else<'a, T>(r: Option<&'a T>, fallback: &'a T) -> &'a T {
            r.unwrap_or(fallback)
        }
        let pick = |i| or_else(i, &irradiance.gathered);
        // An estimate's seed blur image i (0 horizontal, 1 vertical), or the fallback.
        fn seed_of<'a>(e: Option<&'a Estimate>, i: usize, fallback: &'a Image) -> &'a Image {
            e.and_then(|e| e.seed.as_ref())
                .map_or(fallback, |(h, v)| if i == 0 { h } else { v })
        }
        let specular_ref = specular.as_ref();
        let pick_buffer = |b| or_else(b, vpls);
        let set = DescriptorSet::new(
            gpu,
            "interleaved.set",
            &layout,
            &[
                Write::Sampled(0, vec![(&g.position, &sampler)]),
                Write::Sampled(1, vec![(&g.normal, &sampler)]),
                Write::Buffer(2, vpls),
                Write::Buffer(3, pick_buffer(split_position.as_ref())),
                Write::Buffer(4, pick_buffer(split_normal.as_ref())),
                Write::Buffer(5, pick_buffer(irradiance.split.as_ref())),
                Write::Storage(6, &irradiance.gathered),
                Write::Storage(7, seed_of(Some(&irradiance), 0, &irradiance.gathered)),
                Write::Storage(8, seed_of(Some(&irradiance), 1, &irradiance.gathered)),
                Write::Buffer(9, &ctx.scene.lights),
                Write::Buffer(10, sources.points),
                Write::Buffer(11, pick_buffer(specular_ref.and_then(|s| s.split.as_ref()))),
                Write::Storage(12, pick(specular_ref.map(|s| &s.gathered))),
                Write::Storage(13, seed_of(specular_ref, 0, &irradiance.gathered)),
                Write::Storage(14, seed_of(specular_ref, 1, &irradiance.gathered)),
            ],
        )?;
        Ok(SplitPasses {
            split,
            implicit,
            seed,
            floor,
            _layout: layout,
            set,
            _sampler: sampler,
            storage: Storage {
                split_position,
                split_normal,
                irradiance,
                specular,
            },
            mosaic,
            tile: (m, n),
            size: [w as i32, h as i32, ws as i32, hs as i32],
        })
    }

    /// The full-resolution estimates the lighting pass filters: the gathered ones, or with `seed`
    /// their blur.
    pub fn output(&self) -> &Image {
        self.storage.irradiance.output()
    }

    /// `direct`: the full-resolution specular estimates the lighting pass filters (the gathered
    /// ones, or with `seed` their blur).
    pub fn specular_output(&self) -> Option<&Image> {
        self.storage.specular.as_ref().map(Estimate::output)
    }

    /// The estimates: the irradiance, and with `direct` the specular.
    fn estimates(&self) -> impl Iterator<Item = &Estimate> {
        std::iter::once(&self.storage.irradiance).chain(&self.storage.specular)
    }

    /// The split mosaic's side (M Ws x N Hs).
    pub fn mosaic_size(&self) -> (u32, u32) {
        (
            self.tile.0 * self.size[2] as u32,
            self.tile.1 * self.size[3] as u32,
        )
    }

    /// Bytes of the split images and the estimates.
    pub fn bytes(&self) -> u64 {
        let (sw, sh) = self.mosaic_size();
        let split = u64::from(sw) * u64::from(sh);
        let full = self.size[0] as u64 * self.size[1] as u64;
        // Position and normal, then each estimate's mosaic, gathered image and blur images.
        let mut splits = 2 * u64::from(self.storage.split_position.is_some());
        let mut fulls = 0;
        for e in self.estimates() {
            splits += u64::from(e.split.is_some());
            fulls += 1 + 2 * u64::from(e.seed.is_some());
        }
        (splits * split + fulls * full) * 16
    }

    /// Split, shade (with `count` VPLs, clamp `clamp_d2`; with `direct`, the point lights of
    /// `lights`: directional lights, the scene's point lights, extra ones) and gather, or the
    /// implicit pass; then the seed's blur, and the copy floor.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        g: &GBuffer,
        sources: &LightSources,
        count: u32,
        lights: [u32; 3],
        clamp_d2: f32,
    ) -> Result<()> {
        let vpls = sources.vpls;
        let push = SplitPush {
            size: self.size,
            counts: [count, lights[0], lights[1], lights[2]],
            params: [clamp_d2, 0.0, 0.0, 0.0],
        };
        let sh = self.mosaic_size().1;
        // Shade: one invocation per split texel, groups of 8 x 8 texels of one sub-image, z the
        // sub-image (shade.comp). Split and gather: one per M pixels of a row (interleave.glsl's
        // row_word), groups of 64 along the row; the split also covers the padding rows up to
        // N Hs, whose texels it clears.
        let shade_groups = (
            (self.size[2] as u32).div_ceil(8),
            (self.size[3] as u32).div_ceil(8),
            self.tile.0 * self.tile.1,
        );
        let rows = ((self.size[2] as u32).div_ceil(64), self.size[1] as u32, 1);
        let full = (
            (self.size[0] as u32).div_ceil(8),
            (self.size[1] as u32).div_ceil(8),
            1,
        );
        let im = &self.storage;
        cmd.use_image(&g.position, Access::ComputeSampled);
        cmd.use_image(&g.normal, Access::ComputeSampled);
        cmd.use_buffer(vpls, Access::ComputeSampled);
        if im.specular.is_some() {
            cmd.use_buffer(sources.points, Access::ComputeSampled);
        }
        if let Some(implicit) = &self.implicit {
            for e in self.estimates() {
                cmd.use_image(&e.gathered, Access::ComputeStorageWrite);
            }
            self.dispatch(cmd, profiler, implicit, "interleaved.implicit", &push, full);
        }
        if let (Some((split, shade, gather)), Some(sp), Some(sn)) =
            (&self.split, &im.split_position, &im.split_normal)
        {
            // Split: G-buffer -> sub-images.
            cmd.use_buffer(sp, Access::ComputeStorageWrite);
            cmd.use_buffer(sn, Access::ComputeStorageWrite);
            self.dispatch(
                cmd,
                profiler,
                split,
                "interleaved.split",
                &push,
                (rows.0, sh, 1),
            );
            // Shade: sub-image k with subset k.
            cmd.use_buffer(sp, Access::ComputeStorageReadWrite);
            cmd.use_buffer(sn, Access::ComputeStorageReadWrite);
            for b in self.estimates().filter_map(|e| e.split.as_ref()) {
                cmd.use_buffer(b, Access::ComputeStorageWrite);
            }
            self.dispatch(
                cmd,
                profiler,
                shade,
                "interleaved.shade",
                &push,
                shade_groups,
            );
            // Gather: sub-images -> pixels.
            for e in self.estimates() {
                if let Some(b) = &e.split {
                    cmd.use_buffer(b, Access::ComputeStorageReadWrite);
                }
                cmd.use_image(&e.gathered, Access::ComputeStorageWrite);
            }
            self.dispatch(cmd, profiler, gather, "interleaved.gather", &push, rows);
        }
        if let Some((h, v)) = &self.seed {
            let blurs = || {
                self.estimates()
                    .filter_map(|e| Some((&e.gathered, e.seed.as_ref()?)))
            };
            for (gathered, (tmp, _)) in blurs() {
                cmd.use_image(gathered, Access::ComputeStorageReadWrite);
                cmd.use_image(tmp, Access::ComputeStorageWrite);
            }
            self.dispatch(cmd, profiler, h, "interleaved.seed_blur_h", &push, full);
            for (_, (tmp, out)) in blurs() {
                cmd.use_image(tmp, Access::ComputeStorageReadWrite);
                cmd.use_image(out, Access::ComputeStorageWrite);
            }
            self.dispatch(cmd, profiler, v, "interleaved.seed_blur_v", &push, full);
        }
        if let Some(floor) = &self.floor {
            floor.record(cmd, profiler)?;
        }
        Ok(())
    }

    /// Records the copy of the split mosaic (`debug`, split mode).
    pub fn record_readback(&self, cmd: &mut Cmd) {
        if let (Some(rb), Some(si)) = (&self.mosaic, &self.storage.irradiance.split) {
            cmd.read_buffer(si, rb);
        }
    }

    fn dispatch(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        pipeline: &Pipeline,
        name: &str,
        push: &SplitPush,
        (x, y, z): (u32, u32, u32),
    ) {
        let scope = profiler.begin(cmd, name, PassKind::Compute);
        cmd.bind_pipeline(pipeline);
        cmd.bind_set(pipeline, 0, &self.set);
        cmd.push_constants(pipeline, bytemuck::bytes_of(push));
        cmd.dispatch(x, y, z);
        profiler.end(cmd, scope);
    }
}
