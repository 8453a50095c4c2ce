//! The scene raster pass, for the `native` technique (full resolution, one sample at each pixel
//! centre: the reference), for every checkerboard layout and for `interlaced` (the LAYOUT define).

use cbr_gpu::{
    Attachment, Buffer, Cmd, DescriptorSet, Gpu, Layout, PassKind, Pipeline, Profiler, Result,
    Shaders, vk,
};

use crate::gpu_scene::{GpuScene, LIGHT_BINDINGS};
use crate::gpu_types::{MAT_ALBEDO, MAT_BUMP, MAT_MASK};
use crate::layouts::LayoutPlan;
use crate::pass::{Binding, Binds, Filter, GraphicsDecl, GraphicsPass, RasterState, SetDecl, Use};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, GBUFFER_FORMAT, ID_FORMAT, VELOCITY_FORMAT};

/// `LAYOUT` values of the scene shaders (shaders/inc/scene_types.glsl).
pub const LAYOUT_NATIVE: u32 = 0;
pub const LAYOUT_MASKED: u32 = 1;
pub const LAYOUT_SPLIT: u32 = 2;
pub const LAYOUT_ROTATED: u32 = 3;
pub const LAYOUT_MSAA2X: u32 = 4;
/// `interlaced`: native's raster with the rows of the other parity demoted.
pub const LAYOUT_INTERLACED: u32 = 5;

pub fn layout_id(l: Layout) -> u32 {
    match l {
        Layout::Masked => LAYOUT_MASKED,
        Layout::Split => LAYOUT_SPLIT,
        Layout::Rotated => LAYOUT_ROTATED,
        Layout::Msaa2x => LAYOUT_MSAA2X,
    }
}

/// The scene's set: its buffers and the shaded-fragment counter, made once per pass and shared by
/// every raster of the scene (and by `analytic`'s compute passes).
pub const SCENE_SET: SetDecl = SetDecl {
    name: "scene",
    bindings: &[
        Binding::uniform("frame"),
        Binding::buffer("objects", Use::Read),
        Binding::buffer("vertices", Use::Read),
        Binding::buffer("materials", Use::Read),
        LIGHT_BINDINGS[0],
        LIGHT_BINDINGS[1],
        Binding::buffer("counter", Use::Write),
    ],
};

/// One set per material. Separate samplers rather than an indexed array: lavapipe has no
/// `shaderSampledImageArrayDynamicIndexing`. Sampled through the scene's sampler (mipmapped,
/// trilinear); the scene's `anisotropy` is the shader's own lookups (shaders/inc/aniso.glsl).
pub const MATERIAL_SET: SetDecl = SetDecl {
    name: "material",
    bindings: &[
        Binding::sampled_with("albedo", Filter::Given),
        Binding::sampled_with("mask", Filter::Given),
        Binding::sampled_with("bump", Filter::Given),
    ],
};

crate::push_constants! {
    /// Push constants of the scene passes: the object drawn.
    pub struct ScenePush {
        object_index: u32,
    }
}

/// The scene sets' defines (set 0: the scene's, set 1: the material's, and the scene push
/// constants) for shaders whose passes build their pipelines by hand (`analytic`'s).
pub fn shader_defines(layout: u32) -> Vec<(String, String)> {
    let mut d = GraphicsDecl::new("scene", "", "")
        .shared(SCENE_SET)
        .shared(MATERIAL_SET)
        .push::<ScenePush>()
        .stage_defines();
    d.push(("LAYOUT".into(), layout.to_string()));
    d
}

/// How a scene pass rasterises: which layout, into what, with how many instances.
#[derive(Clone, Debug)]
pub struct RasterConfig {
    pub layout: u32,
    pub samples: u32,
    /// Array layers of the targets (split: 2).
    pub layers: u32,
    /// Instances per draw: layers (split), tangram pieces (rotated), else 1.
    pub instances: u32,
    /// Viewport (x, y, width, height) in target pixels.
    pub viewport: [f32; 4],
    /// Depth and IDs only, no shading (the `--id-prepass` pass).
    pub id_only: bool,
    /// Write the ID attachment (off: colour and velocity only, for multisampled targets on
    /// devices without multisampled integer attachments: `msaa`).
    pub write_ids: bool,
    /// Shade every sample (`sampleRateShading`, `minSampleShading = 1`, inputs interpolated at
    /// the sample): msaa2x, `msaa:N:sample`.
    pub sample_shading: bool,
    /// msaa2x with VK_EXT_sample_locations: the frame's two sample locations.
    pub sample_locations: Option<[[f32; 2]; 2]>,
    /// `deferred`'s G-buffer: the surface (position, shading normal, albedo) instead of its
    /// shading, then velocity and IDs (the GBUFFER define of shaders/scene/forward.frag).
    pub gbuffer: bool,
    /// A depth pre-pass first (the alpha test, depth only), then the pass proper with an EQUAL
    /// depth test made before the fragment shader: every pixel's surface is shaded once instead
    /// of every fragment. Only with `gbuffer` (whose outputs do not depend on the shading order).
    pub depth_prepass: bool,
    /// Textures looked up with the screen derivatives rebuilt from the layout's lattice
    /// (`textureGrad`, the LOD_GRADIENTS define) instead of the implicit derivatives plus the
    /// frame's LOD bias. Compiled in, not a frame flag: llvmpipe runs both sides of a branch on a
    /// uniform flag, so a flag would pay for both lookups at every texture tap (docs/OVERVIEW.md).
    pub lod_gradients: bool,
}

impl RasterConfig {
    pub fn native(width: u32, height: u32) -> RasterConfig {
        RasterConfig {
            layout: LAYOUT_NATIVE,
            samples: 1,
            layers: 1,
            instances: 1,
            viewport: [0.0, 0.0, width as f32, height as f32],
            id_only: false,
            write_ids: true,
            sample_shading: false,
            sample_locations: None,
            gbuffer: false,
            depth_prepass: false,
            lod_gradients: false,
        }
    }

    pub fn for_plan(plan: &LayoutPlan) -> RasterConfig {
        let (tw, th) = (plan.target.0 as f32, plan.target.1 as f32);
        // Whole-pixel viewports (lavapipe has no viewport sub-pixel bits); for split and msaa2x the
        // vertex shader scales clip space so that full-res X lands at X / 2 in the target.
        let viewport = match plan.layout {
            Layout::Msaa2x => [plan.viewport_x, 0.0, tw, th],
            _ => [0.0, 0.0, tw, th],
        };
        RasterConfig {
            layout: layout_id(plan.layout),
            samples: plan.samples,
            layers: plan.layers,
            instances: match plan.layout {
                Layout::Split => 2,
                Layout::Rotated => plan.pieces.len() as u32,
                _ => 1,
            },
            viewport,
            id_only: false,
            write_ids: true,
            sample_shading: plan.samples > 1,
            sample_locations: plan.sample_locations,
            gbuffer: false,
            depth_prepass: false,
            lod_gradients: false,
        }
    }
}

/// The pipelines of one combination of material features (MAT_FEATURES).
struct Variant {
    pass: GraphicsPass,
    /// `RasterConfig::depth_prepass`: the depth-only pipeline drawn first, and for bump-mapped
    /// materials the pass proper with late tests (below).
    depth: Option<GraphicsPass>,
    late: Option<GraphicsPass>,
}

/// The declarations of one variant ([`Variant`]).
struct VariantDecls {
    main: GraphicsDecl,
    depth: Option<GraphicsDecl>,
    late: Option<GraphicsDecl>,
}

/// The scene pass's pipelines for `config`, material feature combination `f`.
fn variant_decls(name: &str, config: &RasterConfig, f: u32) -> Result<VariantDecls> {
    if config.depth_prepass && (!config.gbuffer || config.samples != 1) {
        return Err(cbr_gpu::GpuError::Other(format!(
            "{name}: a depth pre-pass is built for the single-sample G-buffer pass only"
        )));
    }
    let mut base = GraphicsDecl::new(
        format!("{name}.mat{f}"),
        "scene/forward.vert",
        "scene/forward.frag",
    )
    .shared(SCENE_SET)
    .shared(MATERIAL_SET)
    .push::<ScenePush>()
    .define("LAYOUT", config.layout)
    .fragment_define("MAT_FEATURES", f)
    .depth("depth", DEPTH_FORMAT);
    for (on, flag) in [
        (config.id_only, "ID_ONLY"),
        (!config.write_ids, "NO_IDS"),
        (config.sample_shading, "SAMPLE_SHADING"),
        (config.gbuffer, "GBUFFER"),
        (config.lod_gradients, "LOD_GRADIENTS"),
    ] {
        if on {
            base = base.define(flag, 1);
        }
    }
    let colors: &[(&'static str, vk::Format)] = match (config.id_only, config.gbuffer) {
        (true, _) => &[("ids", ID_FORMAT)],
        (false, true) => &[
            ("position", GBUFFER_FORMAT),
            ("normal", GBUFFER_FORMAT),
            ("albedo", GBUFFER_FORMAT),
            ("velocity", VELOCITY_FORMAT),
            ("ids", ID_FORMAT),
        ],
        (false, false) if config.write_ids => &[
            ("color", COLOR_FORMAT),
            ("velocity", VELOCITY_FORMAT),
            ("ids", ID_FORMAT),
        ],
        (false, false) => &[("color", COLOR_FORMAT), ("velocity", VELOCITY_FORMAT)],
    };
    // Reverse-Z: nearer is larger. After a depth pre-pass (GREATER, writing), the pass proper
    // tests EQUAL against its depths, so only its surface passes. The same vertex shader bits
    // in every pipeline: the EQUAL test needs the same depths.
    let mut main = base.clone().state(RasterState {
        depth_compare: if config.depth_prepass {
            vk::CompareOp::EQUAL
        } else {
            vk::CompareOp::GREATER
        },
        depth_write: !config.depth_prepass,
        samples: config.samples,
        sample_shading: config.sample_shading,
        sample_locations: config.sample_locations.is_some(),
        ..RasterState::default()
    });
    for (n, format) in colors {
        main = main.color(n, *format);
    }
    if !config.depth_prepass {
        return Ok(VariantDecls {
            main,
            depth: None,
            late: None,
        });
    }
    let depth = GraphicsDecl {
        name: format!("{}.depth", main.name),
        colors: Vec::new(),
        state: RasterState::default(),
        ..base
    }
    .fragment_define("DEPTH_ONLY", 1);
    // Bump mapping differentiates a texture lookup, and on llvmpipe a lane that fails an early
    // depth test does not take part in that derivative (tests/deferred.rs,
    // bump_mapping_matches_native, saw up to 1072 fp16 ulps): bump-mapped materials keep late
    // tests, EQUAL against the pre-pass's depth.
    let late = (f & MAT_BUMP != 0).then(|| GraphicsDecl {
        name: format!("{}.late", main.name),
        ..main.clone()
    });
    Ok(VariantDecls {
        main: main.fragment_define("EARLY_TESTS", 1),
        depth: Some(depth),
        late,
    })
}

/// [`decls`] for the compile-only list (its errors as text).
pub fn listed(
    name: &str,
    config: &RasterConfig,
    features: &[u32],
) -> std::result::Result<Vec<GraphicsDecl>, String> {
    decls(name, config, features).map_err(|e| e.to_string())
}

/// Every pipeline a scene pass builds for `config` and a scene whose materials have `features`
/// (one MAT_FEATURES combination each): the compile-only list's raster entries.
pub fn decls(name: &str, config: &RasterConfig, features: &[u32]) -> Result<Vec<GraphicsDecl>> {
    let mut all = Vec::new();
    for f in feature_variants(features).0 {
        let v = variant_decls(name, config, f)?;
        all.extend([Some(v.main), v.depth, v.late].into_iter().flatten());
    }
    Ok(all)
}

/// The distinct material feature combinations of `features` (sorted; the one with every path
/// when there is none): one pipeline variant each, for passes that declare their own
/// (`analytic`'s raster).
pub fn feature_combinations(features: &[u32]) -> Vec<u32> {
    feature_variants(features).0
}

/// The distinct feature combinations of `features` (sorted) and each entry's index among them;
/// one combination (every path) when there is none.
fn feature_variants(features: &[u32]) -> (Vec<u32>, Vec<usize>) {
    let mut keys: Vec<u32> = features.to_vec();
    keys.sort_unstable();
    keys.dedup();
    if keys.is_empty() {
        keys.push(MAT_ALBEDO | MAT_MASK | MAT_BUMP);
    }
    let index = features
        .iter()
        .map(|f| keys.binary_search(f).unwrap_or(0))
        .collect();
    (keys, index)
}

/// One item (a pipeline, or a pass's pipelines) per combination of material texture paths a
/// scene uses (the MAT_FEATURES define), and which one each material draws with.
pub struct MaterialVariants<P> {
    items: Vec<P>,
    of_material: Vec<usize>,
}

impl<P> MaterialVariants<P> {
    /// `make(f)` builds the item of feature combination f, once per combination in `features`
    /// (one per material).
    pub fn build(features: &[u32], make: impl FnMut(u32) -> Result<P>) -> Result<Self> {
        let (keys, of_material) = feature_variants(features);
        let items = keys.into_iter().map(make).collect::<Result<_>>()?;
        Ok(MaterialVariants { items, of_material })
    }

    /// The item material `m` draws with.
    pub fn of(&self, m: u32) -> &P {
        &self.items[self.of_material[m as usize]]
    }

    /// Any item (there is always one): every variant's pipeline layout is the same, so descriptor
    /// sets bound through one serve them all.
    pub fn first(&self) -> &P {
        &self.items[0]
    }
}

pub struct ScenePass {
    variants: MaterialVariants<Variant>,
    set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    name: String,
}

impl ScenePass {
    /// Builds the pipelines for `config`'s layout and sample count (the same for both parities).
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &GpuScene,
        name: &str,
        config: &RasterConfig,
        counter: &Buffer,
    ) -> Result<ScenePass> {
        let variants = MaterialVariants::build(&scene.material_features, |f| {
            let d = variant_decls(name, config, f)?;
            let build = |d: Option<GraphicsDecl>| d.map(|d| d.build(gpu, shaders)).transpose();
            Ok(Variant {
                pass: d.main.build(gpu, shaders)?,
                depth: build(d.depth)?,
                late: build(d.late)?,
            })
        })?;
        let first = &variants.first().pass;
        let set = SCENE_SET.make(
            gpu,
            name,
            first.layout("scene")?,
            &scene_binds(scene, counter),
        )?;
        let material_sets =
            material_sets(gpu, name, first.layout("material")?, scene, MaskSlot::Mask)?;
        Ok(ScenePass {
            variants,
            set,
            material_sets,
            name: name.to_string(),
        })
    }

    /// `record` into a full set of frame targets (colour, velocity, IDs, depth).
    pub fn record_targets(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        targets: &crate::targets::FrameTargets,
        counter: &Buffer,
        config: &RasterConfig,
    ) -> Result<()> {
        let binds = targets.bind(Binds::new());
        self.record(cmd, profiler, scene, &binds, counter, config)
    }

    /// Clears the colour attachments `binds` name (by the pipeline's names: `color`, `velocity`,
    /// `ids`; `ids` only for `id_only`; `position`, `normal`, `albedo`, `velocity`, `ids` for
    /// `gbuffer`, all cleared to 0) and `depth`, and draws every object. Colour clears to the
    /// background radiance with alpha 1 for native, 0 for the other layouts (checkerboard,
    /// interlaced: alpha marks shaded samples).
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        binds: &Binds,
        counter: &Buffer,
        config: &RasterConfig,
    ) -> Result<()> {
        let first = self.variants.first();
        let (colors, depth) = first.pass.attachments(binds)?;
        let depth = depth.ok_or_else(|| cbr_gpu::GpuError::Other("no depth".into()))?;
        first.pass.prepare(cmd, binds)?;
        use_scene_buffers(cmd, scene);
        cmd.use_buffer(counter, cbr_gpu::Access::FragmentStorageWrite);
        let bg = scene.background;
        let alpha = if config.layout == LAYOUT_NATIVE {
            1.0
        } else {
            0.0
        };
        let attachments: Vec<Attachment> = colors
            .iter()
            .map(|image| {
                let color = match image.format {
                    COLOR_FORMAT => vk::ClearColorValue {
                        float32: [bg[0], bg[1], bg[2], alpha],
                    },
                    ID_FORMAT => vk::ClearColorValue { uint32: [0; 4] },
                    _ => vk::ClearColorValue { float32: [0.0; 4] },
                };
                Attachment {
                    image,
                    clear: Some(vk::ClearValue { color }),
                }
            })
            .collect();
        let depth_clear = vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 0.0,
                stencil: 0,
            },
        };
        let scene_set = Binds::new().shared(&SCENE_SET, &self.set);
        let material = first.pass.set_index("material")?;
        let [x, y, w, h] = config.viewport;
        let prepass = first.depth.is_some();
        if let Some(depth_pass) = &first.depth {
            let scope = profiler.begin(cmd, &format!("{}.depth", self.name), PassKind::Graphics);
            cmd.begin_rendering(
                &[],
                Some(Attachment {
                    image: depth,
                    clear: Some(depth_clear),
                }),
                config.layers,
            );
            cmd.set_viewport(x, y, w, h);
            depth_pass.bind(cmd, &scene_set)?;
            draw_scene(
                cmd,
                scene,
                &self.material_sets,
                material,
                config.instances,
                |m| {
                    self.variants
                        .of(m)
                        .depth
                        .as_ref()
                        .unwrap_or(depth_pass)
                        .pipeline()
                },
            );
            cmd.end_rendering();
            profiler.end(cmd, scope);
        }
        let scope = profiler.begin(cmd, &self.name, PassKind::Graphics);
        cmd.begin_rendering(
            &attachments,
            Some(Attachment {
                image: depth,
                // After the pre-pass, its depths.
                clear: (!prepass).then_some(depth_clear),
            }),
            config.layers,
        );
        cmd.set_viewport(x, y, w, h);
        if let Some(l) = config.sample_locations {
            cmd.set_sample_locations(depth, l);
        }
        first.pass.bind(cmd, &scene_set)?;
        draw_scene(
            cmd,
            scene,
            &self.material_sets,
            material,
            config.instances,
            |m| {
                let v = self.variants.of(m);
                v.late.as_ref().unwrap_or(&v.pass).pipeline()
            },
        );
        cmd.end_rendering();
        profiler.end(cmd, scope);
        Ok(())
    }
}

/// Declares the raster's reads of the scene's buffers (before rendering begins).
pub fn use_scene_buffers(cmd: &mut Cmd, scene: &GpuScene) {
    for buf in [
        &scene.frame,
        &scene.objects,
        &scene.vertices,
        &scene.materials,
        &scene.lights,
        &scene.indices,
    ] {
        cmd.use_buffer(buf, cbr_gpu::Access::GraphicsRead);
    }
}

/// The scene set's resources ([`SCENE_SET`]): `scene`'s buffers and the counter.
pub fn scene_binds<'a>(scene: &'a GpuScene, counter: &'a Buffer) -> Binds<'a> {
    let binds = Binds::new()
        .buffer("frame", &scene.frame)
        .buffer("objects", &scene.objects)
        .buffer("vertices", &scene.vertices)
        .buffer("materials", &scene.materials)
        .buffer("counter", counter);
    scene.bind_lights(binds)
}

/// What an alpha-tested material's mask slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskSlot {
    /// The mask texture itself (sampled at the material's channel).
    Mask,
    /// Its coverage texture ([`GpuScene::material_coverage`]: the passing share in alpha and the
    /// albedo premultiplied by it).
    Coverage,
}

/// One [`MATERIAL_SET`] per material; slots a material does not use hold the 1x1 white
/// texture.
pub fn material_sets(
    gpu: &Gpu,
    name: &str,
    layout: &cbr_gpu::SetLayout,
    scene: &GpuScene,
    mask_slot: MaskSlot,
) -> Result<Vec<DescriptorSet>> {
    scene
        .material_textures
        .iter()
        .zip(&scene.material_coverage)
        .enumerate()
        .map(|(i, (slots, &coverage))| {
            let mask = match mask_slot {
                MaskSlot::Mask => slots[1],
                MaskSlot::Coverage => coverage,
            };
            let tex = |slot: Option<u32>| {
                slot.map(|t| &scene.textures[t as usize])
                    .unwrap_or(&scene.white)
            };
            let binds = Binds::new()
                .sampled("albedo", tex(slots[0]), &scene.sampler)
                .sampled("mask", tex(mask), &scene.sampler)
                .sampled("bump", tex(slots[2]), &scene.sampler);
            MATERIAL_SET.make(gpu, &format!("{name}.material[{i}]"), layout, &binds)
        })
        .collect()
}

/// Draws every object of `scene` with the pipeline `pipeline` picks for its material, bound here
/// when it changes (the scene set bound by the caller; all pipelines' layouts alike, so that a
/// switch keeps it; the material's set at index `material_set`, the object index as push
/// constant), `instances` instances each.
pub fn draw_scene<'a>(
    cmd: &mut Cmd,
    scene: &GpuScene,
    material_sets: &[DescriptorSet],
    material_set: u32,
    instances: u32,
    pipeline: impl Fn(u32) -> &'a Pipeline,
) {
    cmd.bind_index_buffer(&scene.indices);
    let mut bound: Option<&Pipeline> = None;
    for d in &scene.draws {
        let p = pipeline(d.material);
        if !bound.is_some_and(|b| std::ptr::eq(b, p)) {
            cmd.bind_pipeline(p);
            bound = Some(p);
        }
        cmd.bind_set(p, material_set, &material_sets[d.material as usize]);
        let push = ScenePush {
            object_index: d.object,
        };
        cmd.push_constants(p, bytemuck::bytes_of(&push));
        cmd.draw_indexed(d.index_count, instances, d.first_index, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_material_gets_the_variant_of_its_own_features() {
        let features = [
            MAT_ALBEDO | MAT_BUMP,
            0,
            MAT_ALBEDO,
            MAT_ALBEDO | MAT_BUMP,
            MAT_MASK,
        ];
        let (keys, of) = feature_variants(&features);
        assert_eq!(keys, vec![0, MAT_ALBEDO, MAT_MASK, MAT_ALBEDO | MAT_BUMP]);
        for (f, &i) in features.iter().zip(&of) {
            assert_eq!(keys[i], *f);
        }
        // No material: one variant with every path, so the pass still has a pipeline to bind.
        assert_eq!(
            feature_variants(&[]),
            (vec![MAT_ALBEDO | MAT_MASK | MAT_BUMP], vec![])
        );
    }
}
