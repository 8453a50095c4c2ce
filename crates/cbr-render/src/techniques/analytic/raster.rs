//! `analytic`'s two raster passes through the conservative raster (shaders/analytic/raster.geom,
//! raster.frag), declared once ([`GraphicsDecl`]): `analytic.select` (each pixel's K nearest
//! keys) and `analytic.raster` (the kept fragments' slots, the tail records, native's depth,
//! velocity and IDs). The scene's set and the material's are the scene pass's shared sets; the
//! pass's own set is [`RASTER_BINDINGS`] over analytic's resources of those names, made at each
//! draw pass from the frame's binds (so a grown buffer is bound by the next frame).

use cbr_gpu::{Attachment, Cmd, DescriptorSet, GpuError, PassKind, Profiler, Result, vk};

use super::passes::Kernel;
use crate::gpu_scene::GpuScene;
use crate::pass::{Binding, Binds, GraphicsDecl, GraphicsPass, RasterState, Resources, Use};
use crate::scene_pass::{self, MATERIAL_SET, SCENE_SET, ScenePush};
use crate::targets::{DEPTH_FORMAT, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::BuildCtx;

/// The raster passes' own set: analytic's resources of these names (raster.frag; the two it
/// only writes declared so).
pub const RASTER_BINDINGS: [Binding; 16] = [
    Binding::buffer("keys", Use::ReadWrite),
    Binding::buffer("slots", Use::ReadWrite),
    Binding::buffer("counts", Use::ReadWrite),
    Binding::buffer("colors", Use::ReadWrite),
    Binding::buffer("planes", Use::ReadWrite),
    Binding::buffer("planes_y", Use::ReadWrite),
    Binding::buffer("occluders", Use::ReadWrite),
    Binding::buffer("surfaces", Use::ReadWrite),
    Binding::buffer("tail_records", Use::Write),
    Binding::buffer("tail_count", Use::ReadWrite),
    Binding::buffer("cells", Use::ReadWrite),
    Binding::buffer("slot_masks", Use::ReadWrite),
    Binding::buffer("cells_hi", Use::ReadWrite),
    Binding::buffer("albedo_jobs", Use::Write),
    Binding::buffer("albedo_count", Use::ReadWrite),
    Binding::buffer("albedo_bins", Use::ReadWrite),
];

/// The select pass (`select`: each pixel's K nearest keys; its fragments all discard, no depth
/// test or write) or the raster pass of material feature combination `f`.
pub fn decl(k: &Kernel, f: u32, select: bool) -> GraphicsDecl {
    let name = match select {
        true => "analytic.select",
        false => "analytic.raster",
    };
    let mut d = GraphicsDecl::new(
        format!("{name}.mat{f}"),
        "scene/forward.vert",
        "analytic/raster.frag",
    )
    .geometry("analytic/raster.geom")
    .shared(SCENE_SET)
    .shared(MATERIAL_SET)
    .own_set(&RASTER_BINDINGS)
    .push::<ScenePush>()
    .define("LAYOUT", scene_pass::LAYOUT_NATIVE);
    for (n, v) in k.defines() {
        d = d.define(n, v);
    }
    if k.c.seed {
        d = d.define("SEED", 1);
    }
    if k.c.box_filter {
        d = d.define("TEXTURE_BOX", 1);
    }
    d = d.fragment_define("MAT_FEATURES", f);
    if select {
        d = d.fragment_define("SELECT_PASS", 1);
    }
    d.color("velocity", VELOCITY_FORMAT)
        .color("ids", ID_FORMAT)
        .depth("depth", DEPTH_FORMAT)
        .state(RasterState {
            depth_compare: match select {
                true => vk::CompareOp::ALWAYS,
                false => vk::CompareOp::GREATER,
            },
            depth_write: !select,
            ..RasterState::default()
        })
}

/// Every raster pipeline `analytic` builds at `k` for a scene whose materials have `features`:
/// the compile-only list's raster entries.
pub fn decls(k: &Kernel, features: &[u32]) -> Vec<GraphicsDecl> {
    scene_pass::feature_combinations(features)
        .into_iter()
        .flat_map(|f| [decl(k, f, true), decl(k, f, false)])
        .collect()
}

/// One raster pass (select or shade): a pipeline per combination of material texture paths the
/// scene uses (MAT_FEATURES, as the scene pass).
struct Raster {
    pipelines: scene_pass::MaterialVariants<GraphicsPass>,
    name: &'static str,
}

/// The select and raster passes, and the scene's sets they share.
pub struct RasterPasses {
    select: Raster,
    raster: Raster,
    scene_set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
}

impl RasterPasses {
    pub fn new(ctx: &BuildCtx, k: &Kernel) -> Result<RasterPasses> {
        let (gpu, shaders) = (ctx.gpu, ctx.shaders);
        let features = &ctx.scene.material_features;
        let variants = |select: bool| {
            scene_pass::MaterialVariants::build(features, |f| {
                decl(k, f, select).build(gpu, shaders)
            })
        };
        let raster = Raster {
            pipelines: variants(false)?,
            name: "analytic.raster",
        };
        let select = Raster {
            pipelines: variants(true)?,
            name: "analytic.select",
        };
        let first = raster.pipelines.first();
        let scene_set = SCENE_SET.make(
            gpu,
            "analytic",
            first.layout("scene")?,
            &scene_pass::scene_binds(ctx.scene, ctx.counter),
        )?;
        // The mask slot holds the coverage textures: the alpha test and the albedo of the
        // passing part in one lookup (raster.frag).
        let material_sets = scene_pass::material_sets(
            gpu,
            "analytic",
            first.layout("material")?,
            ctx.scene,
            scene_pass::MaskSlot::Coverage,
        )?;
        Ok(RasterPasses {
            select,
            raster,
            scene_set,
            material_sets,
        })
    }

    /// Records the select pass (`select`: it writes no attachment, its fragments all discard) or
    /// the raster pass (which clears the attachments and writes them), over `res`.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        res: &Resources,
        select: bool,
    ) -> Result<()> {
        let (r, clear) = match select {
            true => (&self.select, false),
            false => (&self.raster, true),
        };
        let first = r.pipelines.first();
        let binds = Binds::of(res).shared(&SCENE_SET, &self.scene_set);
        let (colors, depth) = first.attachments(&binds)?;
        let depth = depth.ok_or_else(|| GpuError::Other(format!("{}: no depth", r.name)))?;
        let scope = profiler.begin(cmd, r.name, PassKind::Graphics);
        first.prepare(cmd, &binds)?;
        scene_pass::use_scene_buffers(cmd, scene);
        let attachments: Vec<Attachment> = colors
            .iter()
            .map(|image| Attachment {
                image,
                clear: clear.then_some(vk::ClearValue {
                    color: match image.format {
                        ID_FORMAT => vk::ClearColorValue { uint32: [0; 4] },
                        _ => vk::ClearColorValue { float32: [0.0; 4] },
                    },
                }),
            })
            .collect();
        let depth_clear = clear.then_some(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 0.0,
                stencil: 0,
            },
        });
        cmd.begin_rendering(
            &attachments,
            Some(Attachment {
                image: depth,
                clear: depth_clear,
            }),
            1,
        );
        cmd.set_viewport(0.0, 0.0, depth.width as f32, depth.height as f32);
        first.bind(cmd, &binds)?;
        let material = first.set_index("material")?;
        scene_pass::draw_scene(cmd, scene, &self.material_sets, material, 1, |m| {
            r.pipelines.of(m).pipeline()
        });
        cmd.end_rendering();
        profiler.end(cmd, scope);
        Ok(())
    }
}
