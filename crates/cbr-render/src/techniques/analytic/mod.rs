//! `analytic[:seed][:frags=K]`: anti-aliasing from the exact area of each pixel each triangle
//! covers, instead of from samples (docs/analytic.md).
//!
//! Passes per frame; the first two through the conservative raster (shaders/analytic/raster.geom
//! grows each near-clipped triangle by the pixel square, so every touched pixel is reached
//! without conservative rasterisation): (1) `analytic.select`: each fragment's exact coverage
//! (shaders/analytic/coverage.glsl) and sort key; the pixel keeps its K nearest keys (a 64-bit
//! atomicMin chain, sorted and independent of the order of arrival) and counts every fragment;
//! (2) `analytic.raster`: each fragment among its pixel's K leaves its albedo, normal and shading
//! point (the covered part's centroid) in its slot; the fragments beyond the K that no occluder
//! hides are recorded (shaders/analytic/tail_record.glsl); fragments holding the pixel centre also
//! write native's depth, velocity and IDs; (3) `analytic.tail`: lights the records, one
//! invocation each, into the pixel's tails (fixed-point sums, independent of the order); (4)
//! `analytic.resolve`: front to back per pixel (resolve.comp states the model), lighting only the
//! kept fragments it composites. When a frame records more fragments than the record buffer
//! holds, the buffer grows to what the frame counted and the frame is rendered again (the
//! timings are those of the second rendering). `:seed` replaces the exact area by the seed's column
//! shortcut and flags where it is off; `:frags=K` keeps K fragments per pixel (1 to 64;
//! default 32, lowered to what the device's largest storage buffer holds); `:samples=N` gives
//! the visibility mask N samples (32, 64 the default, or 128; shaders/analytic/mask.glsl); the
//! albedo texture is integrated over the footprint as a box (a grid of lookups, raster.frag's
//! `texture_box`), or with `:aniso` by one anisotropic trilinear filter (the taps along the
//! longer side only).
//!
//! Files: config.rs (the parameters), sizes.rs (bytes per fragment and pixel, capacities),
//! passes.rs (the compute passes and resources, declared once), raster.rs (the two raster
//! passes), reference.rs (the f64 reference of the coverage kernel).

pub mod layers;
mod config;
mod passes;
mod raster;
pub mod reference;
mod sizes;

pub use layers::AnalyticLayers;

use cbr_gpu::{GpuError, Image, PassKind, Readback, Result};
use half::f16;

use super::{Coverage, linear_depths};
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::pass::{Binds, NoPush, Resources};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Outputs, PassList, Registration, Technique};

pub use config::{
    AnalyticConfig, DEFAULT_FRAGS, DEFAULT_SAMPLES, MASK_SAMPLE_COUNTS, MAX_FRAGS, MAX_OBJECTS,
    MAX_PRIMITIVES, parse,
};
pub use passes::{
    AlbedoPush, FLAG_EDGE, FLAG_NONFINITE, FLAG_OVERFLOW, FLAG_SEED, Kernel, READ_IMAGES,
    ResolvePush, albedo_decl, albedo_plan_decl, albedo_scatter_decl, count_readbacks, decls,
    image_readbacks, resolve_decl, resources, tail_decl,
};
pub use raster::{RASTER_BINDINGS, decls as raster_decls};
pub use sizes::*;

pub const REGISTRATION: Registration = Registration {
    name: "analytic",
    grammar: "analytic[:seed][:frags=K][:samples=N][:aniso]",
    about: "exact area of each pixel covered by each triangle, per-pixel fragment lists resolved \
            front to back; `seed`: the seed's column shortcut; `samples=N`: the visibility mask's \
            samples (32, 64, 128); `aniso`: the albedo texture filtered anisotropically, not as a box",
    outputs: Outputs {
        layers: &layers::LAYERS,
        stats: &layers::STATS,
        pngs: Some(layers::debug_pngs),
        settings: None,
    },
    check: |p| parse(p).map(|_| ()),
    needs: config::needs,
    estimate: |ctx, p| {
        let k = Kernel::new(
            parse(p)?,
            ctx.width,
            ctx.height,
            ctx.caps.max_storage_buffer_range,
        )?;
        Ok(Analytic::estimate(&k))
    },
    passes: |ctx, p| {
        let k = Kernel::new(
            parse(p)?,
            ctx.width,
            ctx.height,
            ctx.caps.max_storage_buffer_range,
        )?;
        Ok(PassList {
            compute: decls(&k),
            graphics: raster::decls(&k, ctx.materials),
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("analytic", p, e))?;
        Ok(Box::new(Analytic::new(ctx, c)?))
    },
};

/// The count a compute pass left in the first word of a buffer, read back (`tail_count`,
/// `albedo_count`; some past its buffer's capacity when the frame needed more).
fn count_read(rb: &Readback) -> Result<u64> {
    Ok(u64::from(bytemuck::cast_slice::<u8, u32>(rb.bytes()?)[0]))
}

pub struct Analytic {
    c: AnalyticConfig,
    k: Kernel,
    frags: u32,
    raster: raster::RasterPasses,
    passes: passes::Passes,
    /// The materials the albedo pass runs for, once each with that material's albedo texture:
    /// the textured ones that are not alpha-tested (the ones whose fragments leave jobs).
    albedo_materials: Vec<u32>,
    /// Every buffer and image ([`resources`]); the tail records and the albedo jobs and their
    /// order grow ([`Analytic::grow_tail_records`], [`Analytic::grow_albedo_jobs`]).
    res: Resources,
    tail_count_rb: Readback,
    albedo_count_rb: Readback,
    readbacks: [Readback; 6],
    background: [f32; 3],
}

impl Analytic {
    /// What [`Analytic::new`] keeps at `k`: the declared resources ([`resources`]: the fragment
    /// lists, tails, occluders, records and jobs at their starting capacity, the resolved
    /// colour, coverage and counts, native's velocity, ID and depth targets), the six image
    /// readbacks and the two counts read back.
    pub fn estimate(k: &Kernel) -> MemoryEstimate {
        let mut e = crate::pass::estimate(&resources(k), "analytic");
        e.append(crate::pass::estimate(&image_readbacks(k), "readback"));
        e.append(crate::pass::estimate(&count_readbacks(), "readback"));
        e
    }

    pub fn new(ctx: &BuildCtx, c: AnalyticConfig) -> Result<Analytic> {
        let gpu = ctx.gpu;
        let k = Kernel::new(
            c,
            ctx.width,
            ctx.height,
            gpu.caps().max_storage_buffer_range,
        )
        .map_err(GpuError::Other)?;
        if ctx.scene.draws.len() > MAX_OBJECTS
            || ctx
                .scene
                .draws
                .iter()
                .any(|d| d.index_count as usize / 3 > MAX_PRIMITIVES)
        {
            return Err(GpuError::Other(format!(
                "analytic keys fragments by object (< {}) and primitive (< {MAX_PRIMITIVES}); this \
                 scene has {} objects, the largest with {} triangles",
                MAX_OBJECTS + 1,
                ctx.scene.draws.len(),
                ctx.scene
                    .draws
                    .iter()
                    .map(|d| d.index_count / 3)
                    .max()
                    .unwrap_or(0)
            )));
        }
        if ctx.scene.material_textures.len() > MAX_MATERIALS {
            return Err(GpuError::Other(format!(
                "analytic orders its albedo lookups by material, at most {MAX_MATERIALS}; this \
                 scene has {}",
                ctx.scene.material_textures.len()
            )));
        }
        let res = Resources::new(gpu, "analytic", &resources(&k))?;
        let raster = raster::RasterPasses::new(ctx, &k)?;
        let passes = passes::Passes::new(gpu, ctx.shaders, &k)?;
        // The materials whose fragments leave albedo jobs (raster.frag: an albedo texture, no
        // alpha test).
        let albedo_materials: Vec<u32> = ctx
            .scene
            .material_textures
            .iter()
            .zip(0u32..)
            .filter(|(t, _)| t[0].is_some() && t[1].is_none())
            .map(|(_, m)| m)
            .collect();
        let [tail_count_rb, albedo_count_rb] =
            count_readbacks().map(|d| d.make_readback(gpu, "readback"));
        let [r0, r1, r2, r3, r4, r5] =
            image_readbacks(&k).map(|d| d.make_readback(gpu, "readback"));
        let readbacks = [r0?, r1?, r2?, r3?, r4?, r5?];
        Ok(Analytic {
            c,
            frags: k.frags,
            k,
            raster,
            passes,
            albedo_materials,
            res,
            tail_count_rb: tail_count_rb?,
            albedo_count_rb: albedo_count_rb?,
            readbacks,
            background: ctx.scene.background,
        })
    }

    /// Fragments kept per pixel this technique was built with.
    pub fn kept_per_pixel(&self) -> u32 {
        self.frags
    }

    /// Records and submits the frame's passes once (render() checks the tail records' count).
    fn submit_frame(&self, ctx: &mut FrameCtx, world_from_clip: [f32; 16]) -> Result<()> {
        let counter = ctx.counter;
        ctx.submit("frame", |cmd, profiler, scene| {
            let res = &self.res;
            let buf = |name: &str| res.buffer(name);
            let scope = profiler.begin(cmd, "analytic.clear", PassKind::Transfer);
            cmd.fill_buffer(buf("keys")?, u32::MAX);
            for name in ["counts", "tail", "tail_back", "tail_masks", "occluders"] {
                cmd.fill_buffer(buf(name)?, 0);
            }
            // No records yet; the tail pass's dispatch: rows of TAIL_ROW_GROUPS groups, none.
            cmd.update_buffer(buf("tail_count")?, &[0, TAIL_ROW_GROUPS, 0, 1]);
            cmd.update_buffer(buf("albedo_count")?, &[0, TAIL_ROW_GROUPS, 0, 1]);
            cmd.fill_buffer(buf("albedo_bins")?, 0);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, cbr_gpu::Access::FragmentStorageWrite);
            // The select pass writes no attachment (its fragments all discard); the second pass
            // clears and writes them.
            self.raster.record(cmd, profiler, scene, res, true)?;
            self.raster.record(cmd, profiler, scene, res, false)?;

            // What every compute pass binds: the resources and the scene's buffers by name,
            // each pass taking (and barriering) the ones it declares.
            let binds = scene.bind_lights(
                Binds::of(res)
                    .buffer("frame", &scene.frame)
                    .buffer("objects", &scene.objects)
                    .buffer("materials", &scene.materials),
            );
            let p = &self.passes;

            // The albedo pass: the textured fragments' lookups, one invocation per job, once per
            // material over that material's jobs (ordered by material first: the plan's offsets
            // and dispatches, then the scatter). Each dispatch writes other slots and records
            // than the one before, but the same buffers: the barriers between them follow from
            // the declared uses; the bins are read as the dispatches' parameters too.
            let scope = profiler.begin(cmd, "analytic.albedo", PassKind::Compute);
            let plan = binds.only(&p.plan);
            p.plan.prepare(cmd, &plan)?;
            p.plan
                .dispatch_untimed(cmd, &plan, &NoPush::default(), [1, 1, 1])?;
            let scatter = binds.only(&p.scatter);
            let args = (buf("albedo_count")?, 4);
            p.scatter.prepare_indirect(cmd, &scatter, args.0)?;
            p.scatter
                .dispatch_indirect_untimed(cmd, &scatter, &NoPush::default(), args)?;
            let bins = buf("albedo_bins")?;
            for &m in &self.albedo_materials {
                let texture = scene.material_textures[m as usize][0]
                    .map_or(&scene.white, |t| &scene.textures[t as usize]);
                let albedo =
                    binds
                        .only(&p.albedo)
                        .sampled("albedo_texture", texture, &scene.sampler);
                let args = (bins, u64::from(m) * ALBEDO_BIN_BYTES + 16);
                p.albedo.prepare_indirect(cmd, &albedo, bins)?;
                p.albedo.dispatch_indirect_untimed(
                    cmd,
                    &albedo,
                    &AlbedoPush { material: m },
                    args,
                )?;
            }
            profiler.end(cmd, scope);

            // The tail pass: one invocation per record the buffer holds, in the rows the raster
            // pass counted (the count may run past the capacity: render() then grows the buffer
            // and renders again).
            let tail = binds.only(&p.tail);
            let args = (buf("tail_count")?, 4);
            p.tail
                .dispatch_indirect(cmd, profiler, &tail, &NoPush::default(), args)?;

            let size = (self.k.width, self.k.height);
            let bg = self.background;
            let push = ResolvePush {
                background: [bg[0], bg[1], bg[2], 0.0],
                size: [size.0, size.1, 0, 0],
                world_from_clip: bytemuck::cast(world_from_clip),
            };
            p.resolve
                .dispatch_2d(cmd, profiler, &binds.only(&p.resolve), &push, size)?;

            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            for (name, rb) in READ_IMAGES.iter().zip(&self.readbacks) {
                cmd.read_image(res.image(name)?, rb);
            }
            for (name, rb) in [
                ("tail_count", &self.tail_count_rb),
                ("albedo_count", &self.albedo_count_rb),
            ] {
                cmd.use_buffer(buf(name)?, cbr_gpu::Access::TransferSrc);
                cmd.read_buffer(buf(name)?, rb);
            }
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    /// Albedo jobs the last submitted frame asked for (some beyond the capacity when it exceeds
    /// it).
    fn recorded_jobs(&self) -> Result<u64> {
        count_read(&self.albedo_count_rb)
    }

    /// Albedo jobs the buffer holds.
    fn job_capacity(&self) -> Result<u64> {
        Ok(self.res.buffer("albedo_jobs")?.size() / ALBEDO_JOB_BYTES)
    }

    /// Tail records the buffer holds.
    fn tail_capacity(&self) -> Result<u64> {
        Ok(self.res.buffer("tail_records")?.size() / tail_record_bytes(self.c.samples))
    }

    /// Fragments the last submitted frame recorded for the tails (some beyond the capacity
    /// when it exceeds it).
    fn recorded_tails(&self) -> Result<u64> {
        count_read(&self.tail_count_rb)
    }

    /// Replaces the tail-record buffer by one holding `needed` records and a quarter more (at most
    /// the device's largest storage buffer); or the refusal where one buffer cannot hold `needed`.
    /// The frame that counted them has completed (FrameCtx::submit waits), so nothing uses the
    /// old buffer; every pass makes its set from the frame's binds, so the next frame binds the
    /// new one.
    fn grow_tail_records(&mut self, gpu: &cbr_gpu::Gpu, needed: u64) -> Result<()> {
        let samples = self.c.samples;
        let capacity = grown_tail_capacity(needed, self.frags, samples, self.k.max_range)
            .map_err(GpuError::Other)?;
        tracing::info!(
            "analytic: {needed} tail records this frame, {} held: the buffer grows to {capacity}",
            self.tail_capacity()?
        );
        self.res
            .grow(gpu, "tail_records", capacity * tail_record_bytes(samples))
    }

    /// Replaces the albedo-job buffer (and the jobs' order) by one holding `needed` jobs and a
    /// quarter more (at most the device's largest storage buffer); or the refusal where one buffer
    /// cannot hold `needed`. As [`Analytic::grow_tail_records`].
    fn grow_albedo_jobs(&mut self, gpu: &cbr_gpu::Gpu, needed: u64) -> Result<()> {
        let capacity = grown_job_capacity(needed, self.k.max_range).map_err(GpuError::Other)?;
        tracing::info!(
            "analytic: {needed} albedo jobs this frame, {} held: the buffer grows to {capacity}",
            self.job_capacity()?
        );
        self.res
            .grow(gpu, "albedo_jobs", capacity * ALBEDO_JOB_BYTES)?;
        self.res
            .grow(gpu, "albedo_order", capacity * ALBEDO_ORDER_BYTES)
    }
}

impl Technique for Analytic {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        // Camera-relative world from unjittered clip space, the inverse of what gpu_scene.rs
        // builds every object's clip_from_local from (f64, then f32).
        let cam = &view.camera;
        let world_from_clip = (cam.projection(view.aspect) * cam.rotation())
            .inverse()
            .to_cols_array()
            .map(|v| v as f32);
        let timings_before = ctx.timings.clone();
        loop {
            self.submit_frame(ctx, world_from_clip)?;
            let recorded = self.recorded_tails()?;
            let jobs = self.recorded_jobs()?;
            let (tails_held, jobs_held) = (self.tail_capacity()?, self.job_capacity()?);
            if recorded <= tails_held && jobs <= jobs_held {
                return Ok(());
            }
            // More fragments beyond the K, or textured fragments, than a buffer holds: grow it
            // and render the frame again (its timings replace the first rendering's).
            if recorded > tails_held {
                self.grow_tail_records(ctx.gpu, recorded)?;
            }
            if jobs > jobs_held {
                self.grow_albedo_jobs(ctx.gpu, jobs)?;
            }
            ctx.timings = timings_before.clone();
        }
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        self.res.image("out_color").ok()
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        let r = &self.res;
        Some(Geometry {
            velocity: r.image("velocity").ok()?,
            depth: r.image("depth").ok()?,
            ids: r.image("ids").ok()?,
            packed: false,
        })
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let [c, cov, cnt, d, v, ids] = &self.readbacks;
        let mut out = FrameOutput::new(
            ctx.view.width,
            ctx.view.height,
            bytemuck::cast_slice::<u8, f16>(c.bytes()?).to_vec(),
            linear_depths(bytemuck::cast_slice(d.bytes()?), ctx.view.camera.near),
            bytemuck::cast_slice::<u8, [f32; 2]>(v.bytes()?).to_vec(),
            bytemuck::cast_slice::<u8, [u32; 2]>(ids.bytes()?).to_vec(),
        );
        let counts: &[[u32; 4]] = bytemuck::cast_slice(cnt.bytes()?);
        let coverage = Coverage {
            edge: counts
                .iter()
                .map(|c| u8::from(c[2] & FLAG_EDGE != 0))
                .collect(),
            fraction: bytemuck::cast_slice::<u8, f32>(cov.bytes()?).to_vec(),
        };
        AnalyticLayers {
            fragments: counts.iter().map(|c| c[0]).collect(),
            overflow: counts.iter().map(|c| c[1]).collect(),
            visible: counts.iter().map(|c| c[3]).collect(),
            seed_differs: counts
                .iter()
                .map(|c| u8::from(self.c.seed && c[2] & FLAG_SEED != 0))
                .collect(),
            nonfinite: counts
                .iter()
                .map(|c| u8::from(c[2] & FLAG_NONFINITE != 0))
                .collect(),
            kept_per_pixel: self.frags,
            tail_fragments: self.recorded_tails()?,
            albedo_jobs: self.recorded_jobs()?,
        }
        .write(&coverage, &mut out)?;
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let tail_records = self.res.buffer("tail_records").map_or(0, |b| b.size());
        let k = &self.k;
        sizes::target_bytes(k.px(), k.frags, k.c.samples, k.occluder_group, tail_records)
    }
}
