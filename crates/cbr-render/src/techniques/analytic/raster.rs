//! `analytic`'s two raster passes through the conservative raster (shaders/analytic/raster.geom,
//! raster.frag): `analytic.select` (each pixel's K nearest keys) and `analytic.raster` (the kept
//! fragments' slots, the tail records, native's depth, velocity and IDs). Set 0 is the scene's,
//! set 1 the material's, set 2 [`RASTER_BINDINGS`] over analytic's resources, written by
//! binding name.

use cbr_gpu::{
    Access, Attachment, BindingDesc, Cmd, DescriptorKind, DescriptorSet, Gpu, GraphicsDesc,
    PassKind, Pipeline, Profiler, Result, SetLayout, Write, vk,
};

use super::passes::Kernel;
use crate::gpu_scene::GpuScene;
use crate::pass::Resources;
use crate::scene_pass::{self, BINDINGS as SCENE_BINDINGS, MATERIAL_BINDINGS};
use crate::targets::{DEPTH_FORMAT, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::BuildCtx;

/// Set 2 of the raster passes (set 0: the scene's, set 1: the material's): analytic's resources
/// of these names.
pub const RASTER_BINDINGS: [BindingDesc; 16] = {
    use DescriptorKind::StorageBuffer as B;
    [
        BindingDesc::one("keys", 0, B),
        BindingDesc::one("slots", 1, B),
        BindingDesc::one("counts", 2, B),
        BindingDesc::one("colors", 3, B),
        BindingDesc::one("planes", 4, B),
        BindingDesc::one("planes_y", 5, B),
        BindingDesc::one("occluders", 6, B),
        BindingDesc::one("surfaces", 7, B),
        BindingDesc::one("tail_records", 8, B),
        BindingDesc::one("tail_count", 9, B),
        BindingDesc::one("cells", 10, B),
        BindingDesc::one("slot_masks", 11, B),
        BindingDesc::one("cells_hi", 12, B),
        BindingDesc::one("albedo_jobs", 13, B),
        BindingDesc::one("albedo_count", 14, B),
        BindingDesc::one("albedo_bins", 15, B),
    ]
};

/// One raster pass (select or shade): a pipeline per combination of material texture paths the
/// scene uses (MAT_FEATURES, as the scene pass).
struct Raster {
    pipelines: scene_pass::MaterialVariants<Pipeline>,
    name: &'static str,
}

/// The select and raster passes, and their sets.
pub struct RasterPasses {
    select: Raster,
    raster: Raster,
    scene_set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    raster_layout: SetLayout,
    raster_set: DescriptorSet,
    _layouts: [SetLayout; 2],
}

/// Set 2's writes: each binding of [`RASTER_BINDINGS`] to the resource of its name.
fn writes(res: &Resources) -> Result<Vec<Write<'_>>> {
    RASTER_BINDINGS
        .iter()
        .map(|b| Ok(Write::Buffer(b.binding, res.buffer(b.name)?)))
        .collect()
}

impl RasterPasses {
    pub fn new(ctx: &BuildCtx, k: &Kernel, res: &Resources) -> Result<RasterPasses> {
        let gpu = ctx.gpu;
        let scene_layout = SetLayout::new(gpu, "analytic.scene_layout", &SCENE_BINDINGS)?;
        let material_layout = SetLayout::new(gpu, "analytic.material_layout", &MATERIAL_BINDINGS)?;
        let raster_layout = SetLayout::new(gpu, "analytic.raster_layout", &RASTER_BINDINGS)?;
        let mut defines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        defines.extend(RASTER_BINDINGS.iter().map(BindingDesc::define));
        defines.extend(k.defines().map(|(n, v)| (n.to_string(), v)));
        if k.c.seed {
            defines.push(("SEED".into(), "1".into()));
        }
        if k.c.box_filter {
            defines.push(("TEXTURE_BOX".into(), "1".into()));
        }
        let vs = ctx.shaders.compile("scene/forward.vert", &defines)?;
        let gs = ctx.shaders.compile("analytic/raster.geom", &defines)?;
        let layouts = [&scene_layout, &material_layout, &raster_layout];
        let graphics = |name: &'static str, select: bool| -> Result<Raster> {
            let pipelines =
                scene_pass::MaterialVariants::build(&ctx.scene.material_features, |f| {
                    let mut d = defines.clone();
                    d.push(("MAT_FEATURES".into(), f.to_string()));
                    if select {
                        d.push(("SELECT_PASS".into(), "1".into()));
                    }
                    let fs = ctx.shaders.compile("analytic/raster.frag", &d)?;
                    Pipeline::graphics(
                        gpu,
                        &GraphicsDesc {
                            name: &format!("{name}.mat{f}"),
                            vertex: &vs,
                            geometry: Some(&gs),
                            fragment: &fs,
                            set_layouts: &layouts,
                            push_constant_bytes: 4,
                            color_formats: &[VELOCITY_FORMAT, ID_FORMAT],
                            depth_format: Some(DEPTH_FORMAT),
                            depth_compare: if select {
                                vk::CompareOp::ALWAYS
                            } else {
                                vk::CompareOp::GREATER
                            },
                            depth_write: !select,
                            samples: 1,
                            min_sample_shading: None,
                            cull_back_faces: false,
                            sample_locations: false,
                        },
                    )
                })?;
            Ok(Raster { pipelines, name })
        };
        let raster = graphics("analytic.raster", false)?;
        let select = graphics("analytic.select", true)?;
        let scene_set =
            scene_pass::scene_set(gpu, "analytic", &scene_layout, ctx.scene, ctx.counter)?;
        // The mask slot holds the coverage textures: the alpha test and the albedo of the
        // passing part in one lookup (raster.frag).
        let material_sets = scene_pass::material_sets(
            gpu,
            "analytic",
            &material_layout,
            ctx.scene,
            scene_pass::MaskSlot::Coverage,
        )?;
        let raster_set =
            DescriptorSet::new(gpu, "analytic.raster_set", &raster_layout, &writes(res)?)?;
        Ok(RasterPasses {
            select,
            raster,
            scene_set,
            material_sets,
            raster_layout,
            raster_set,
            _layouts: [scene_layout, material_layout],
        })
    }

    /// Points set 2 at `res`'s buffers again, after one grew (the frame that bound the old one
    /// has completed: FrameCtx::submit waits).
    pub fn rebind(&self, gpu: &Gpu, res: &Resources) -> Result<()> {
        self.raster_set
            .update(gpu, &self.raster_layout, &writes(res)?)
    }

    /// Records the select pass (`select`: it writes no attachment, its fragments all discard) or
    /// the raster pass (which clears the attachments and writes them).
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
        let scope = profiler.begin(cmd, r.name, PassKind::Graphics);
        scene_pass::use_scene_buffers(cmd, scene);
        for b in &RASTER_BINDINGS {
            cmd.use_buffer(res.buffer(b.name)?, Access::FragmentStorageWrite);
        }
        let color_clear = |uint: bool| {
            clear.then_some(vk::ClearValue {
                color: if uint {
                    vk::ClearColorValue { uint32: [0; 4] }
                } else {
                    vk::ClearColorValue { float32: [0.0; 4] }
                },
            })
        };
        let depth_clear = clear.then_some(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 0.0,
                stencil: 0,
            },
        });
        let depth = res.image("depth")?;
        cmd.begin_rendering(
            &[
                Attachment {
                    image: res.image("velocity")?,
                    clear: color_clear(false),
                },
                Attachment {
                    image: res.image("ids")?,
                    clear: color_clear(true),
                },
            ],
            Some(Attachment {
                image: depth,
                clear: depth_clear,
            }),
            1,
        );
        cmd.set_viewport(0.0, 0.0, depth.width as f32, depth.height as f32);
        cmd.bind_set(r.pipelines.first(), 0, &self.scene_set);
        cmd.bind_set(r.pipelines.first(), 2, &self.raster_set);
        scene_pass::draw_scene(cmd, scene, &self.material_sets, 1, |m| r.pipelines.of(m));
        cmd.end_rendering();
        profiler.end(cmd, scope);
        Ok(())
    }
}
