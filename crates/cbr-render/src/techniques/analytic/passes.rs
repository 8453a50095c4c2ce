//! `analytic`'s compute passes and resources, each declared once (crate::pass): the albedo
//! pass and the two that order its jobs by material (albedo_bin.comp), the tail pass and the
//! resolve. Their bindings are by name (the scene's buffers too: set 0 holds everything a pass
//! reads), their barriers follow from each binding's declared use, the resolve's flag bits and
//! the kernel's sizes are defines from Rust. [`decls`] is the compile-only list
//! (`Registration::passes`); [`Passes::new`] builds the same declarations.

use cbr_gpu::{Gpu, Result, Shaders, vk};

use super::config::AnalyticConfig;
use super::reference;
use super::sizes::{
    ALBEDO_BIN_BYTES, ALBEDO_COUNT_BYTES, ALBEDO_JOB_BYTES, ALBEDO_ORDER_BYTES, HALF_CELLS_BYTES,
    HALF_SLOT_BYTES, KEY_BYTES, MAX_MATERIALS, PLANE_XY_BYTES, PLANE_Y_BYTES, SURFACE_BYTES,
    TAIL_BYTES, TAIL_COUNT_BYTES, TAIL_ROW_GROUPS, occluder_bytes, occluder_group, plan_lists,
    slot_mask_bytes, start_job_capacity, start_tail_capacity, tail_mask_bytes, tail_record_bytes,
};
use crate::pass::{Binding, ComputeDecl, ComputePass, Filter, ResourceDecl, Use};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, ID_FORMAT, VELOCITY_FORMAT};

/// Bits of the counts image's third channel (resolve.comp takes them from here).
pub const FLAG_EDGE: u32 = 1;
pub const FLAG_SEED: u32 = 2;
pub const FLAG_OVERFLOW: u32 = 4;
pub const FLAG_NONFINITE: u32 = 8;

const COVERAGE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
const COUNTS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// Invocations per group of the passes that run one invocation per record or job (the rows of
/// tail_record.glsl's TailCount and albedo_job.glsl's AlbedoCount are counted in groups of 64).
const LIST_GROUP: u32 = 64;

crate::push_constants! {
    /// The resolve's push constants (resolve.comp).
    pub struct ResolvePush {
        /// rgb: the background radiance.
        background: [f32; 4],
        /// Width, height.
        size: [u32; 4],
        /// Camera-relative world from unjittered clip space.
        world_from_clip: [[f32; 4]; 4],
    }
}

crate::push_constants! {
    /// The albedo pass's push constants (albedo.comp): the material whose jobs it runs.
    pub struct AlbedoPush {
        material: u32,
    }
}

/// A configuration fitted to a size and a device: what every pass and buffer is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernel {
    pub c: AnalyticConfig,
    /// Fragments kept per pixel ([`plan_lists`]).
    pub frags: u32,
    /// Samples per occluder word ([`occluder_group`]).
    pub occluder_group: u32,
    pub width: u32,
    pub height: u32,
    /// The device's `maxStorageBufferRange`.
    pub max_range: u32,
}

impl Kernel {
    /// `c` at `width` x `height` on a device binding at most `max_range` bytes in one storage
    /// buffer, or the refusal where the kept fragments cannot fit.
    pub fn new(
        c: AnalyticConfig,
        width: u32,
        height: u32,
        max_range: u32,
    ) -> std::result::Result<Kernel, String> {
        let frags = plan_lists(width, height, c.frags, c.samples, max_range)?;
        let occluder_group = occluder_group(Kernel::px_of(width, height), max_range, c.samples);
        Ok(Kernel {
            c,
            frags,
            occluder_group,
            width,
            height,
            max_range,
        })
    }

    fn px_of(width: u32, height: u32) -> u64 {
        u64::from(width) * u64::from(height)
    }

    pub fn px(&self) -> u64 {
        Kernel::px_of(self.width, self.height)
    }

    /// The defines every analytic shader is compiled with (the raster's too).
    pub fn defines(&self) -> [(&'static str, String); 5] {
        [
            ("K_SLOTS", self.frags.to_string()),
            ("OCCLUDER_GROUP", self.occluder_group.to_string()),
            ("TAIL_ROW_GROUPS", TAIL_ROW_GROUPS.to_string()),
            ("MASK_SAMPLES", self.c.samples.to_string()),
            (
                "MASK_GEN",
                reference::mask_generator(self.c.samples).to_string(),
            ),
        ]
    }

    fn decl(&self, name: &str, shader: &'static str) -> ComputeDecl {
        self.defines()
            .into_iter()
            .fold(ComputeDecl::new(name, shader), |d, (k, v)| d.define(k, v))
    }
}

/// The scene's buffers the lighting reads (shaders/inc/shading.glsl), bound by name.
const SCENE_LIGHTING: [Binding; 4] = [
    Binding::uniform("frame"),
    Binding::buffer("materials", Use::Read),
    crate::gpu_scene::LIGHT_BINDINGS[0],
    crate::gpu_scene::LIGHT_BINDINGS[1],
];

/// The plan of the albedo jobs' order (albedo_bin.comp with BIN_PLAN, one invocation): each
/// material's offset and dispatch.
pub fn albedo_plan_decl(k: &Kernel) -> ComputeDecl {
    k.decl("analytic.albedo_plan", "analytic/albedo_bin.comp")
        .define("BIN_PLAN", 1)
        .bind(Binding::buffer("albedo_bins", Use::ReadWrite))
        .group(LIST_GROUP, 1)
}

/// The scatter of the albedo jobs into material order (albedo_bin.comp, one invocation per job,
/// dispatched indirectly in the raster pass's rows).
pub fn albedo_scatter_decl(k: &Kernel) -> ComputeDecl {
    k.decl("analytic.albedo_scatter", "analytic/albedo_bin.comp")
        .bindings(&[
            Binding::buffer("albedo_jobs", Use::Read),
            Binding::buffer("albedo_count", Use::Read),
            Binding::buffer("albedo_bins", Use::ReadWrite),
            Binding::buffer("albedo_order", Use::Write),
        ])
        .group(LIST_GROUP, 1)
}

/// The albedo pass (albedo.comp): one material's jobs, its albedo texture read through the
/// scene's sampler.
pub fn albedo_decl(k: &Kernel) -> ComputeDecl {
    let d = k
        .decl("analytic.albedo", "analytic/albedo.comp")
        .bindings(&[
            Binding::buffer("albedo_jobs", Use::Read),
            Binding::buffer("albedo_bins", Use::Read),
            Binding::buffer("albedo_order", Use::Read),
            Binding::buffer("colors", Use::ReadWrite),
            Binding::buffer("cells", Use::Write),
            Binding::buffer("cells_hi", Use::Write),
            Binding::buffer("tail_records", Use::ReadWrite),
            Binding::uniform("frame"),
            Binding::buffer("materials", Use::Read),
            Binding::sampled_with("albedo_texture", Filter::Given),
        ])
        .push::<AlbedoPush>()
        .group(LIST_GROUP, 1);
    if k.c.box_filter {
        d.define("TEXTURE_BOX", 1)
    } else {
        d
    }
}

/// The tail pass (tail.comp): lights the recorded fragments beyond the K nearest into their
/// pixels' tails; dispatched indirectly in the rows the raster pass counted.
pub fn tail_decl(k: &Kernel) -> ComputeDecl {
    k.decl("analytic.tail", "analytic/tail.comp")
        .bindings(&[
            Binding::buffer("tail_records", Use::Read),
            Binding::buffer("tail_count", Use::Read),
            Binding::buffer("tail", Use::ReadWrite),
            Binding::buffer("tail_back", Use::ReadWrite),
            Binding::buffer("tail_masks", Use::ReadWrite),
        ])
        .bindings(&SCENE_LIGHTING)
        .group(LIST_GROUP, 1)
}

/// The resolve (resolve.comp): each pixel's kept fragments front to back, lit, and its tails.
pub fn resolve_decl(k: &Kernel) -> ComputeDecl {
    k.decl("analytic.resolve", "analytic/resolve.comp")
        .constants(&[
            ("FLAG_EDGE", FLAG_EDGE),
            ("FLAG_SEED", FLAG_SEED),
            ("FLAG_OVERFLOW", FLAG_OVERFLOW),
            ("FLAG_NONFINITE", FLAG_NONFINITE),
        ])
        .bindings(&[
            Binding::buffer("keys", Use::Read),
            Binding::buffer("slots", Use::Read),
            Binding::buffer("slot_masks", Use::Read),
            Binding::buffer("colors", Use::Read),
            Binding::buffer("counts", Use::Read),
            Binding::buffer("tail", Use::Read),
            Binding::buffer("tail_back", Use::Read),
            Binding::buffer("tail_masks", Use::Read),
            Binding::buffer("planes", Use::Read),
            Binding::buffer("planes_y", Use::Read),
            Binding::buffer("surfaces", Use::Read),
            Binding::buffer("cells", Use::Read),
            Binding::buffer("cells_hi", Use::Read),
            Binding::buffer("objects", Use::Read),
            Binding::image("out_color", Use::Write),
            Binding::image("out_coverage", Use::Write),
            Binding::image("out_counts", Use::Write),
        ])
        .bindings(&SCENE_LIGHTING)
        .push::<ResolvePush>()
        .group(8, 8)
}

/// Every compute pass [`Passes::new`] builds for `k`: the compile-only list.
pub fn decls(k: &Kernel) -> Vec<ComputeDecl> {
    vec![
        albedo_plan_decl(k),
        albedo_scatter_decl(k),
        albedo_decl(k),
        tail_decl(k),
        resolve_decl(k),
    ]
}

/// The built compute passes.
pub struct Passes {
    pub plan: ComputePass,
    pub scatter: ComputePass,
    pub albedo: ComputePass,
    pub tail: ComputePass,
    pub resolve: ComputePass,
}

impl Passes {
    /// Builds [`decls`]'s passes.
    pub fn new(gpu: &Gpu, shaders: &Shaders, k: &Kernel) -> Result<Passes> {
        Ok(Passes {
            plan: albedo_plan_decl(k).build(gpu, shaders)?,
            scatter: albedo_scatter_decl(k).build(gpu, shaders)?,
            albedo: albedo_decl(k).build(gpu, shaders)?,
            tail: tail_decl(k).build(gpu, shaders)?,
            resolve: resolve_decl(k).build(gpu, shaders)?,
        })
    }
}

/// The images read back each frame, by resource name, in the order of their readbacks
/// ([`image_readbacks`], `Analytic::readbacks`): colour, coverage, counts, depth, velocity, IDs.
pub const READ_IMAGES: [&str; 6] = [
    "out_color",
    "out_coverage",
    "out_counts",
    "depth",
    "velocity",
    "ids",
];

/// The readbacks of [`READ_IMAGES`] (allocated as `readback.analytic.<layer>`).
pub fn image_readbacks(k: &Kernel) -> [ResourceDecl; 6] {
    let rb = |name, format| ResourceDecl::readback(name, format, k.width, k.height);
    [
        rb("analytic.color", COLOR_FORMAT),
        rb("analytic.coverage", COVERAGE_FORMAT),
        rb("analytic.counts", COUNTS_FORMAT),
        rb("analytic.depth", DEPTH_FORMAT),
        rb("analytic.velocity", VELOCITY_FORMAT),
        rb("analytic.ids", ID_FORMAT),
    ]
}

/// The readbacks of the two counts the frame's passes leave (`tail_count`, `albedo_count`: the
/// first word of each).
pub fn count_readbacks() -> [ResourceDecl; 2] {
    let rb = |name| ResourceDecl::readback(name, vk::Format::R32_UINT, 1, 1);
    [rb("analytic.tail_count"), rb("analytic.albedo_count")]
}

/// Every buffer and image `analytic` owns at `k` (allocated as `analytic.<name>`), bound by
/// these names by the compute passes and the raster's set. The buffers of tail records and of
/// albedo jobs (and their order) are declared at their starting capacity and grow to what a
/// frame needs (`Resources::grow`; the estimate is the start).
pub fn resources(k: &Kernel) -> Vec<ResourceDecl> {
    let (w, h, samples) = (k.width, k.height, k.c.samples);
    let px = k.px();
    let kept = px * u64::from(k.frags);
    let b = ResourceDecl::buffer;
    let jobs = start_job_capacity(px, k.max_range);
    let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
    vec![
        b("keys", kept * KEY_BYTES),
        b("slots", kept * HALF_SLOT_BYTES),
        b("colors", kept * HALF_SLOT_BYTES),
        b("planes", kept * PLANE_XY_BYTES),
        b("planes_y", kept * PLANE_Y_BYTES),
        b("surfaces", kept * SURFACE_BYTES),
        b("cells", kept * HALF_CELLS_BYTES),
        b("cells_hi", kept * HALF_CELLS_BYTES),
        b("slot_masks", (kept * slot_mask_bytes(samples)).max(4)),
        b("counts", px * 4),
        b("tail", px * TAIL_BYTES),
        b("tail_back", px * TAIL_BYTES),
        b("tail_masks", px * tail_mask_bytes(samples)),
        b("occluders", occluder_bytes(px, k.max_range, samples)),
        b(
            "tail_records",
            start_tail_capacity(px, k.max_range, samples) * tail_record_bytes(samples),
        ),
        b("tail_count", TAIL_COUNT_BYTES).indirect(),
        b("albedo_jobs", jobs * ALBEDO_JOB_BYTES),
        b("albedo_count", ALBEDO_COUNT_BYTES).indirect(),
        b("albedo_bins", MAX_MATERIALS as u64 * ALBEDO_BIN_BYTES).indirect(),
        b("albedo_order", jobs * ALBEDO_ORDER_BYTES),
        ResourceDecl::image("out_color", COLOR_FORMAT, w, h),
        ResourceDecl::image("out_coverage", COVERAGE_FORMAT, w, h),
        ResourceDecl::image("out_counts", COUNTS_FORMAT, w, h),
        // Native's layers, written by the raster where a triangle holds the pixel centre (read
        // back, and sampled by temporal post passes).
        ResourceDecl::attachment("velocity", VELOCITY_FORMAT, w, h, 1).usage(sampled),
        ResourceDecl::attachment("ids", ID_FORMAT, w, h, 1).usage(sampled),
        ResourceDecl::attachment("depth", DEPTH_FORMAT, w, h, 1).usage(sampled),
    ]
}
