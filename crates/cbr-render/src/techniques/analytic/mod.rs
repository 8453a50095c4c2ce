//! `analytic[:seed][:nocull][:frags=N]`: anti-aliasing from the exact area of each pixel each
//! triangle covers, instead of from samples (docs/analytic.md).
//!
//! Passes per frame: (1) `analytic.cull`: the conservative raster (shaders/analytic/raster.geom
//! grows each near-clipped triangle by the pixel square, so every touched pixel is reached
//! without conservative rasterisation) records per pixel the farthest depth of the opaque
//! triangles that cover it entirely; (2) `analytic.raster`: the same raster computes each
//! fragment's exact coverage (shaders/analytic/coverage.glsl), drops what lies wholly behind the
//! bound, shades at the covered part's centroid and appends to the pixel's linked fragment list
//! in a fixed pool; fragments holding the pixel centre also write native's depth, velocity and
//! IDs; (3) `analytic.resolve`: front to back per pixel (resolve.comp states the model).
//! `:seed` replaces the exact area by the seed's column shortcut and flags where it is off;
//! `:nocull` skips pass 1 (for measuring what it saves); `:frags=N` sizes the pool at N
//! fragments per pixel (default 8, lowered to what the device's largest storage buffer holds).

pub mod reference;

use cbr_gpu::{
    Access, BindingDesc, Buffer, Caps, ComputeDesc, DescriptorKind, DescriptorSet, GpuError,
    GraphicsDesc, Image, ImageDesc, Location, PassKind, Pipeline, Readback, Result, SetLayout,
    Write, vk,
};
use half::f16;

use super::linear_depths;
use crate::renderer::{AnalyticLayers, Coverage, FrameOutput};
use crate::scene_pass::{self, BINDINGS as SCENE_BINDINGS, MATERIAL_BINDINGS};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};

pub const REGISTRATION: Registration = Registration {
    name: "analytic",
    grammar: "analytic[:seed][:nocull][:frags=N]",
    about: "exact area of each pixel covered by each triangle, per-pixel fragment lists resolved \
            front to back; `seed`: the seed's column shortcut",
    layers: &["coverage", "analytic"],
    check: |p| parse(p).map(|_| ()),
    needs,
    build: |ctx, p| {
        let c = parse(p).map_err(GpuError::Other)?;
        Ok(Box::new(Analytic::new(ctx, c)?))
    },
};

/// Bytes of one fragment in the pool: next, depth, coverage, mask, colour (3 x f16) + flags and
/// object ID, primitive ID.
pub const NODE_BYTES: u64 = 28;
/// Fragment-pool slots per pixel unless `frags=N` says otherwise.
pub const DEFAULT_FRAGS: u32 = 8;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnalyticConfig {
    pub seed: bool,
    pub cull: bool,
    /// Pool slots per pixel asked for (`None`: the default, fitted to the device).
    pub frags: Option<u32>,
}

pub fn parse(params: &[&str]) -> std::result::Result<AnalyticConfig, String> {
    let mut c = AnalyticConfig {
        seed: false,
        cull: true,
        frags: None,
    };
    for p in params {
        match *p {
            "seed" => c.seed = true,
            "nocull" => c.cull = false,
            _ => match p.strip_prefix("frags=") {
                Some(n) => {
                    let n: u32 = n
                        .parse()
                        .ok()
                        .filter(|&n| (1..=256).contains(&n))
                        .ok_or_else(|| format!("analytic frags=`{n}` (1 to 256)"))?;
                    c.frags = Some(n);
                }
                None => return Err(unknown_param("analytic", p, "seed, nocull, frags=N")),
            },
        }
    }
    Ok(c)
}

fn needs(_: &[&str], caps: &Caps) -> Option<String> {
    if !caps.geometry_shader {
        return Some("the geometryShader feature (the conservative raster)".into());
    }
    (!caps.fragment_stores_and_atomics)
        .then(|| "the fragmentStoresAndAtomics feature (fragment lists)".into())
}

/// The fragment pool for `width` x `height`: slots per pixel, or the refusal (before anything is
/// allocated) with the bytes it would take and the device's limit. The pool is one storage
/// buffer, so it must fit `maxStorageBufferRange`.
pub fn plan_pool(
    width: u32,
    height: u32,
    frags: Option<u32>,
    max_range: u32,
) -> std::result::Result<u32, String> {
    let px = u64::from(width) * u64::from(height);
    let fit = (u64::from(max_range) / (px * NODE_BYTES).max(1)).min(u64::from(u32::MAX)) as u32;
    let want = frags.unwrap_or(DEFAULT_FRAGS);
    let refuse = |f: u32| {
        format!(
            "analytic at {width}x{height} with {f} fragments per pixel needs a fragment pool of \
             {} bytes ({f} x {NODE_BYTES} bytes per pixel); this device binds at most {max_range} \
             bytes in one storage buffer (maxStorageBufferRange): lower the resolution or \
             frags=N (at most {fit} fits)",
            px * u64::from(f) * NODE_BYTES
        )
    };
    match frags {
        Some(f) if f > fit => Err(refuse(f)),
        Some(f) => Ok(f),
        None if fit >= 2 => Ok(want.min(fit)),
        None => Err(refuse(2)),
    }
}

/// Set 2 of the raster passes (set 0: the scene's, set 1: the material's).
pub const RASTER_BINDINGS: [BindingDesc; 5] = {
    use DescriptorKind::StorageBuffer as B;
    [
        BindingDesc::one("heads", 0, B),
        BindingDesc::one("nodes", 1, B),
        BindingDesc::one("bound", 2, B),
        BindingDesc::one("lost", 3, B),
        BindingDesc::one("stats", 4, B),
    ]
};

pub const RESOLVE_BINDINGS: [BindingDesc; 6] = {
    use DescriptorKind::{StorageBuffer as B, StorageImage as I};
    [
        BindingDesc::one("heads", 0, B),
        BindingDesc::one("nodes", 1, B),
        BindingDesc::one("lost", 2, B),
        BindingDesc::one("out_color", 3, I),
        BindingDesc::one("out_coverage", 4, I),
        BindingDesc::one("out_counts", 5, I),
    ]
};

/// Bits of the counts image's third channel (resolve.comp).
pub const FLAG_EDGE: u32 = 1;
pub const FLAG_SEED: u32 = 2;
pub const FLAG_OVERFLOW: u32 = 4;

const COVERAGE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
const COUNTS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// Native's layers, written by the list pass where a triangle holds the pixel centre.
struct Targets {
    velocity: Image,
    ids: Image,
    depth: Image,
}

struct Raster {
    pipeline: Pipeline,
    name: &'static str,
}

pub struct Analytic {
    c: AnalyticConfig,
    frags: u32,
    cull: Option<Raster>,
    raster: Raster,
    _layouts: Vec<SetLayout>,
    scene_set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    raster_set: DescriptorSet,
    resolve: Pipeline,
    resolve_set: DescriptorSet,
    heads: Buffer,
    nodes: Buffer,
    bound: Buffer,
    lost: Buffer,
    stats: Buffer,
    stats_rb: Buffer,
    targets: Targets,
    color: Image,
    coverage: Image,
    counts: Image,
    readbacks: [Readback; 6],
    background: [f32; 3],
}

impl Analytic {
    pub fn new(ctx: &BuildCtx, c: AnalyticConfig) -> Result<Analytic> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let frags = plan_pool(w, h, c.frags, gpu.caps().max_storage_buffer_range)
            .map_err(GpuError::Other)?;
        let px = u64::from(w) * u64::from(h);
        let capacity = px * u64::from(frags);
        let scene_layout = SetLayout::new(gpu, "analytic.scene_layout", &SCENE_BINDINGS)?;
        let material_layout = SetLayout::new(gpu, "analytic.material_layout", &MATERIAL_BINDINGS)?;
        let raster_layout = SetLayout::new(gpu, "analytic.raster_layout", &RASTER_BINDINGS)?;
        let resolve_layout = SetLayout::new(gpu, "analytic.resolve_layout", &RESOLVE_BINDINGS)?;

        let mut defines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        defines.extend(RASTER_BINDINGS.iter().map(BindingDesc::define));
        defines.push(("NODE_CAPACITY".into(), format!("{capacity}u")));
        defines.push(("NODE_WORDS".into(), format!("{}u", NODE_BYTES / 4)));
        if c.seed {
            defines.push(("SEED".into(), "1".into()));
        }
        let vs = ctx.shaders.compile("scene/forward.vert", &defines)?;
        let gs = ctx.shaders.compile("analytic/raster.geom", &defines)?;
        let fs = ctx.shaders.compile("analytic/raster.frag", &defines)?;
        let layouts = [&scene_layout, &material_layout, &raster_layout];
        let graphics = |name: &'static str, fs: &[u32], write: bool| -> Result<Raster> {
            let pipeline = Pipeline::graphics(
                gpu,
                &GraphicsDesc {
                    name,
                    vertex: &vs,
                    geometry: Some(&gs),
                    fragment: fs,
                    set_layouts: &layouts,
                    push_constant_bytes: 4,
                    color_formats: &[VELOCITY_FORMAT, ID_FORMAT],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_compare: if write {
                        vk::CompareOp::GREATER
                    } else {
                        vk::CompareOp::ALWAYS
                    },
                    depth_write: write,
                    samples: 1,
                    min_sample_shading: None,
                    cull_back_faces: false,
                    sample_locations: false,
                },
            )?;
            Ok(Raster { pipeline, name })
        };
        let raster = graphics("analytic.raster", &fs, true)?;
        let cull = if c.cull {
            let mut d = defines.clone();
            d.push(("CULL_PASS".into(), "1".into()));
            let fs = ctx.shaders.compile("analytic/raster.frag", &d)?;
            Some(graphics("analytic.cull", &fs, false)?)
        } else {
            None
        };

        let mut rdefines: Vec<(String, String)> =
            RESOLVE_BINDINGS.iter().map(BindingDesc::define).collect();
        rdefines.push(("NODE_WORDS".into(), format!("{}u", NODE_BYTES / 4)));
        let cs = ctx.shaders.compile("analytic/resolve.comp", &rdefines)?;
        let resolve = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "analytic.resolve",
                shader: &cs,
                set_layouts: &[&resolve_layout],
                push_constant_bytes: 32,
            },
        )?;

        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let buffer =
            |name: &str, bytes: u64, usage| Buffer::new(gpu, name, bytes, usage, Location::GpuOnly);
        let heads = buffer("analytic.heads", px * 4, storage)?;
        let nodes = buffer("analytic.nodes", capacity * NODE_BYTES, storage)?;
        let bound = buffer("analytic.bound", px * 4, storage)?;
        let lost = buffer("analytic.lost", px * 4, storage)?;
        let stats = buffer(
            "analytic.stats",
            16,
            storage | vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        let stats_rb = Buffer::new(
            gpu,
            "analytic.stats_readback",
            16,
            vk::BufferUsageFlags::TRANSFER_DST,
            Location::GpuToCpu,
        )?;
        // Native's colour target is not drawn (the resolve writes the colour).
        let FrameTargets {
            velocity,
            ids,
            depth,
            ..
        } = FrameTargets::new(gpu, "analytic", w, h)?;
        let targets_color = {
            let usage = vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC;
            move |name: &str, format| Image::new(gpu, &ImageDesc::new_2d(name, format, w, h, usage))
        };
        let color = targets_color("analytic.color", COLOR_FORMAT)?;
        let coverage = targets_color("analytic.coverage", COVERAGE_FORMAT)?;
        let counts = targets_color("analytic.counts", COUNTS_FORMAT)?;
        let targets = Targets {
            velocity,
            ids,
            depth,
        };

        let scene_set =
            scene_pass::scene_set(gpu, "analytic", &scene_layout, ctx.scene, ctx.counter)?;
        let material_sets =
            scene_pass::material_sets(gpu, "analytic", &material_layout, ctx.scene)?;
        let raster_set = DescriptorSet::new(
            gpu,
            "analytic.raster_set",
            &raster_layout,
            &[
                Write::Buffer(0, &heads),
                Write::Buffer(1, &nodes),
                Write::Buffer(2, &bound),
                Write::Buffer(3, &lost),
                Write::Buffer(4, &stats),
            ],
        )?;
        let resolve_set = DescriptorSet::new(
            gpu,
            "analytic.resolve_set",
            &resolve_layout,
            &[
                Write::Buffer(0, &heads),
                Write::Buffer(1, &nodes),
                Write::Buffer(2, &lost),
                Write::Storage(3, &color),
                Write::Storage(4, &coverage),
                Write::Storage(5, &counts),
            ],
        )?;
        let rb = |name: &str, image: &Image| Readback::for_image(gpu, name, image);
        let readbacks = [
            rb("readback.analytic.color", &color)?,
            rb("readback.analytic.coverage", &coverage)?,
            rb("readback.analytic.counts", &counts)?,
            rb("readback.analytic.depth", &targets.depth)?,
            rb("readback.analytic.velocity", &targets.velocity)?,
            rb("readback.analytic.ids", &targets.ids)?,
        ];
        Ok(Analytic {
            c,
            frags,
            cull,
            raster,
            _layouts: vec![scene_layout, material_layout, raster_layout, resolve_layout],
            scene_set,
            material_sets,
            raster_set,
            resolve,
            resolve_set,
            heads,
            nodes,
            bound,
            lost,
            stats,
            stats_rb,
            targets,
            color,
            coverage,
            counts,
            readbacks,
            background: ctx.scene.background,
        })
    }

    /// Fragment-pool slots per pixel this technique was built with.
    pub fn pool_per_pixel(&self) -> u32 {
        self.frags
    }

    fn record_raster(
        &self,
        cmd: &mut cbr_gpu::Cmd,
        profiler: &mut cbr_gpu::Profiler,
        scene: &crate::gpu_scene::GpuScene,
        r: &Raster,
        clear: bool,
    ) {
        let scope = profiler.begin(cmd, r.name, PassKind::Graphics);
        for buf in [
            &scene.frame,
            &scene.objects,
            &scene.vertices,
            &scene.materials,
            &scene.lights,
            &scene.indices,
        ] {
            cmd.use_buffer(buf, Access::GraphicsRead);
        }
        for buf in [
            &self.heads,
            &self.nodes,
            &self.bound,
            &self.lost,
            &self.stats,
        ] {
            cmd.use_buffer(buf, Access::FragmentStorageWrite);
        }
        let t = &self.targets;
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
        cmd.begin_rendering(
            &[
                cbr_gpu::Attachment {
                    image: &t.velocity,
                    clear: color_clear(false),
                },
                cbr_gpu::Attachment {
                    image: &t.ids,
                    clear: color_clear(true),
                },
            ],
            Some(cbr_gpu::Attachment {
                image: &t.depth,
                clear: depth_clear,
            }),
            1,
        );
        cmd.set_viewport(0.0, 0.0, t.depth.width as f32, t.depth.height as f32);
        cmd.bind_pipeline(&r.pipeline);
        cmd.bind_set(&r.pipeline, 0, &self.scene_set);
        cmd.bind_set(&r.pipeline, 2, &self.raster_set);
        scene_pass::draw_scene(cmd, &r.pipeline, scene, &self.material_sets, 1);
        cmd.end_rendering();
        profiler.end(cmd, scope);
    }
}

impl Technique for Analytic {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let this = &*self;
        let counter = ctx.counter;
        ctx.submit("frame", |cmd, profiler, scene| {
            let scope = profiler.begin(cmd, "analytic.clear", PassKind::Transfer);
            cmd.fill_buffer(&this.heads, u32::MAX);
            cmd.fill_buffer(&this.bound, 0);
            cmd.fill_buffer(&this.lost, 0);
            cmd.fill_buffer(&this.stats, 0);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::FragmentStorageWrite);
            // The cull pass writes no attachment (its fragments all discard); the list pass
            // clears and writes them.
            if let Some(cull) = &this.cull {
                this.record_raster(cmd, profiler, scene, cull, false);
            }
            this.record_raster(cmd, profiler, scene, &this.raster, true);

            for buf in [&this.heads, &this.nodes, &this.lost] {
                cmd.use_buffer(buf, Access::ComputeSampled);
            }
            for img in [&this.color, &this.coverage, &this.counts] {
                cmd.use_image(img, Access::ComputeStorageWrite);
            }
            let scope = profiler.begin(cmd, "analytic.resolve", PassKind::Compute);
            cmd.bind_pipeline(&this.resolve);
            cmd.bind_set(&this.resolve, 0, &this.resolve_set);
            let (w, h) = (this.color.width, this.color.height);
            let bg = this.background;
            let mut push = [0u32; 8];
            push[..3].copy_from_slice(&bg.map(f32::to_bits));
            push[4] = w;
            push[5] = h;
            cmd.push_constants(&this.resolve, bytemuck::cast_slice(&push));
            cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            profiler.end(cmd, scope);

            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            let [c, cov, cnt, d, v, ids] = &this.readbacks;
            cmd.read_image(&this.color, c);
            cmd.read_image(&this.coverage, cov);
            cmd.read_image(&this.counts, cnt);
            cmd.read_image(&this.targets.depth, d);
            cmd.read_image(&this.targets.velocity, v);
            cmd.read_image(&this.targets.ids, ids);
            cmd.copy_buffer(&this.stats, &this.stats_rb, 16);
            cmd.use_buffer(&this.stats_rb, Access::HostRead);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        let t = &self.targets;
        Some(Geometry {
            velocity: &t.velocity,
            depth: &t.depth,
            ids: &t.ids,
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
        out.coverage = Some(Coverage {
            edge: counts
                .iter()
                .map(|c| u8::from(c[2] & FLAG_EDGE != 0))
                .collect(),
            fraction: bytemuck::cast_slice::<u8, f32>(cov.bytes()?).to_vec(),
        });
        out.analytic = Some(AnalyticLayers {
            fragments: counts.iter().map(|c| c[0]).collect(),
            overflow: counts.iter().map(|c| c[1]).collect(),
            visible: counts.iter().map(|c| c[3]).collect(),
            seed_differs: counts
                .iter()
                .map(|c| u8::from(self.c.seed && c[2] & FLAG_SEED != 0))
                .collect(),
            pool_per_pixel: self.frags,
        });
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let px = u64::from(self.color.width) * u64::from(self.color.height);
        // Pool + heads, bound, lost (4 each) + colour (8), coverage (4), counts (16), depth (4),
        // velocity (8), IDs (8).
        px * (u64::from(self.frags) * NODE_BYTES + 12 + 8 + 4 + 16 + 4 + 8 + 8)
    }
}
