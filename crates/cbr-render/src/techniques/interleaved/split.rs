//! `interleaved`'s passes between the G-buffer and the lighting pass (shaders/interleaved/):
//! `interleaved.split` (the G-buffer into M x N sub-images), `interleaved.shade` (sub-image k with
//! VPL subset k) and `interleaved.gather` (the estimates back to their pixels); with `implicit`
//! the one pass `interleaved.implicit` instead (each pixel its own position's subset, no split);
//! with `seed` the seed's blur, `interleaved.seed_blur_h` and `interleaved.seed_blur_v`; with
//! `floor` a copy kernel moving the split and gather passes' bytes (`interleaved.copy_floor`).
//! One set layout and one set serve every pipeline.

use cbr_gpu::{Buffer, Cmd, Image, Profiler, Readback, Result, vk};

use super::{Filter, InterleavedConfig};
use crate::gpu_scene::{GpuScene, LIGHT_BINDINGS};
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Use};
use crate::resolve::CopyFloor;
use crate::targets::GBUFFER_FORMAT;
use crate::technique::BuildCtx;
use crate::techniques::deferred::GBuffer;
use crate::techniques::deferred::lighting::{LightSources, POINT_BINDINGS, VPL_BINDINGS};

crate::push_constants! {
    /// Push constants (interleave.glsl's).
    pub struct SplitPush {
        /// W, H, Ws, Hs.
        size: [i32; 4],
        /// x: VPLs; with `direct`: y the scene's directional lights, z its point lights, w the
        /// extra point lights (`points=N`).
        counts: [u32; 4],
        /// x: the VPL clamp c (m^2).
        params: [f32; 4],
    }
}

/// What every pass of the split shares: the tile, `direct`, the push constants.
fn base(name: &str, shader: &'static str, c: &InterleavedConfig) -> ComputeDecl {
    let mut d = ComputeDecl::new(name, shader)
        .define("TILE_M", c.m)
        .define("TILE_N", c.n)
        .push::<SplitPush>();
    if c.direct {
        d = d.define("DIRECT", 1);
    }
    d
}

/// The G-buffer surface the split, the implicit pass and the seed's edge test read.
const SURFACE: [Binding; 2] = [Binding::sampled("position"), Binding::sampled("normal")];

/// Split: the G-buffer into the sub-images (shaders/interleaved/split.comp), one invocation per
/// M pixels of a row.
pub fn split_decl(c: &InterleavedConfig) -> ComputeDecl {
    base("interleaved.split", "interleaved/split.comp", c)
        .bindings(&SURFACE)
        .bind(Binding::buffer("split_position", Use::Write))
        .bind(Binding::buffer("split_normal", Use::Write))
        .group(64, 1)
}

/// Shade: sub-image k with VPL subset k (and with `direct` point-light subset k).
pub fn shade_decl(c: &InterleavedConfig) -> ComputeDecl {
    let mut d = base("interleaved.shade", "interleaved/shade.comp", c).bindings(&[
        VPL_BINDINGS[0],
        VPL_BINDINGS[1],
        // shading.glsl's light term reads the scene's lights.
        LIGHT_BINDINGS[0],
        LIGHT_BINDINGS[1],
        Binding::buffer("split_position", Use::ReadWrite),
        Binding::buffer("split_normal", Use::ReadWrite),
        Binding::buffer("split_irradiance", Use::Write),
    ]);
    if c.direct {
        d = d.bindings(&[
            POINT_BINDINGS[0],
            POINT_BINDINGS[1],
            Binding::buffer("split_specular", Use::Write),
        ]);
    }
    d
}

/// The gather's (or the implicit pass's) flags: DEBUG the round trip, SEED the seed's edges.
fn flags(mut d: ComputeDecl, c: &InterleavedConfig) -> ComputeDecl {
    if c.debug {
        d = d.define("DEBUG", 1);
    }
    if c.filter == Filter::Seed {
        d = d.define("SEED", 1);
    }
    d
}

/// Gather: the sub-images back to pixels (`box`: each pixel's window row summed, BOX_ROWS).
pub fn gather_decl(c: &InterleavedConfig) -> ComputeDecl {
    let mut d = flags(base("interleaved.gather", "interleaved/gather.comp", c), c).bindings(&[
        Binding::buffer("split_irradiance", Use::ReadWrite),
        Binding::image("irradiance", Use::Write),
    ]);
    if c.box_rows() {
        d = d.define("BOX_ROWS", 1);
    }
    if c.direct {
        d = d.bindings(&[
            Binding::buffer("split_specular", Use::ReadWrite),
            Binding::image("specular", Use::Write),
        ]);
    }
    if c.debug || c.filter == Filter::Seed {
        d = d.bindings(&SURFACE);
    }
    if c.debug {
        d = d.bindings(&[
            Binding::buffer("split_position", Use::ReadWrite),
            Binding::buffer("split_normal", Use::ReadWrite),
        ]);
    }
    d.group(64, 1)
}

/// `implicit`: every pixel shades its own subset at full resolution, no split.
pub fn implicit_decl(c: &InterleavedConfig) -> ComputeDecl {
    let mut d = flags(
        base("interleaved.implicit", "interleaved/implicit.comp", c),
        c,
    )
    .bindings(&SURFACE)
    .bindings(&VPL_BINDINGS)
    .bindings(&LIGHT_BINDINGS)
    .bind(Binding::image("irradiance", Use::Write));
    if c.direct {
        d = d.bindings(&[
            POINT_BINDINGS[0],
            POINT_BINDINGS[1],
            Binding::image("specular", Use::Write),
        ]);
    }
    d
}

/// `seed`: the seed's blur, one direction per pass (shaders/interleaved/seed_blur.comp).
pub fn seed_decl(c: &InterleavedConfig, horizontal: bool) -> ComputeDecl {
    let (name, from, to, from_s, to_s) = match horizontal {
        true => (
            "interleaved.seed_blur_h",
            "irradiance",
            "seed_tmp",
            "specular",
            "seed_tmp_specular",
        ),
        false => (
            "interleaved.seed_blur_v",
            "seed_tmp",
            "seed_out",
            "seed_tmp_specular",
            "seed_out_specular",
        ),
    };
    let mut d = base(name, "interleaved/seed_blur.comp", c)
        .bind(Binding::image(from, Use::ReadWrite))
        .bind(Binding::image(to, Use::Write));
    if horizontal {
        d = d.define("HORIZONTAL", 1);
    }
    if c.direct {
        d = d
            .bind(Binding::image(from_s, Use::ReadWrite))
            .bind(Binding::image(to_s, Use::Write));
    }
    d
}

/// Every pass the configuration builds, in recording order (the compile-only list).
pub fn decls(c: &InterleavedConfig) -> Vec<ComputeDecl> {
    let mut d = match c.implicit {
        true => vec![implicit_decl(c)],
        false => vec![split_decl(c), shade_decl(c), gather_decl(c)],
    };
    if c.filter == Filter::Seed {
        d.push(seed_decl(c, true));
        d.push(seed_decl(c, false));
    }
    d
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

/// What the split passes allocate under `interleaved`: the split mosaic's buffers (one vec4 of
/// f32 per texel; not with `implicit`): position, normal and per estimate its own; the
/// full-resolution estimates (irradiance, `direct`: specular), and with `seed` each estimate's
/// two blur images.
fn resources(config: &InterleavedConfig, w: u32, h: u32) -> Vec<ResourceDecl> {
    let (ws, hs) = sub_image(w, h, config.m, config.n);
    let bytes = u64::from(config.m * ws) * u64::from(config.n * hs) * MOSAIC_WORD;
    let mut r = Vec::new();
    let mut estimate = |split: &'static str, gathered, seed: [&'static str; 2]| {
        if !config.implicit {
            r.push(ResourceDecl::buffer(split, bytes));
        }
        r.push(ResourceDecl::image(gathered, GBUFFER_FORMAT, w, h));
        if config.filter == Filter::Seed {
            r.extend(seed.map(|n| ResourceDecl::image(n, GBUFFER_FORMAT, w, h)));
        }
    };
    estimate("split_irradiance", "irradiance", ["seed_tmp", "seed_out"]);
    if config.direct {
        estimate(
            "split_specular",
            "specular",
            ["seed_tmp_specular", "seed_out_specular"],
        );
    }
    if !config.implicit {
        r.push(ResourceDecl::buffer("split_position", bytes));
        r.push(ResourceDecl::buffer("split_normal", bytes));
    }
    r
}

/// `debug` with a split: the readback of the irradiance mosaic (`readback.interleaved_mosaic`).
fn mosaic_readback(config: &InterleavedConfig, w: u32, h: u32) -> Option<ResourceDecl> {
    let (ws, hs) = sub_image(w, h, config.m, config.n);
    (config.debug && !config.implicit).then(|| {
        ResourceDecl::readback(
            "interleaved_mosaic",
            vk::Format::R32G32B32A32_SFLOAT,
            config.m * ws,
            config.n * hs,
        )
    })
}

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
    split: Option<(ComputePass, ComputePass, ComputePass)>,
    implicit: Option<ComputePass>,
    seed: Option<(ComputePass, ComputePass)>,
    floor: Option<CopyFloor>,
    storage: Storage,
    /// `debug`: the split mosaic of the estimates, read back each frame.
    pub mosaic: Option<Readback>,
    tile: (u32, u32),
    size: [i32; 4],
}

impl SplitPasses {
    /// What [`SplitPasses::new`] allocates.
    pub fn estimate(e: &mut MemoryEstimate, config: &InterleavedConfig, w: u32, h: u32) {
        e.append(crate::pass::estimate(
            &resources(config, w, h),
            "interleaved",
        ));
        if let Some(rb) = mosaic_readback(config, w, h) {
            e.append(crate::pass::estimate(&[rb], "readback"));
        }
        if config.floor {
            CopyFloor::estimate(e, FLOOR, moved_bytes(w, h));
        }
    }

    pub fn new(ctx: &BuildCtx, config: &InterleavedConfig) -> Result<SplitPasses> {
        let gpu = ctx.gpu;
        let (m, n) = (config.m, config.n);
        let build = |d: ComputeDecl| d.build(gpu, ctx.shaders);
        let (split, implicit) = if config.implicit {
            (None, Some(build(implicit_decl(config))?))
        } else {
            let passes = (
                build(split_decl(config))?,
                build(shade_decl(config))?,
                build(gather_decl(config))?,
            );
            (Some(passes), None)
        };
        let seed = if config.filter == Filter::Seed {
            Some((
                build(seed_decl(config, true))?,
                build(seed_decl(config, false))?,
            ))
        } else {
            None
        };
        let (w, h) = (ctx.width, ctx.height);
        let (ws, hs) = sub_image(w, h, m, n);
        let decls = resources(config, w, h);
        let decl = |name: &str| {
            decls
                .iter()
                .find(|d| d.name == name)
                .ok_or_else(|| cbr_gpu::GpuError::Other(format!("interleaved: no `{name}`")))
        };
        let buffer = |name: &str| -> Result<Option<Buffer>> {
            match config.implicit {
                true => Ok(None),
                false => decl(name)?.make_buffer(gpu, "interleaved").map(Some),
            }
        };
        let img = |name: &str| decl(name)?.make_image(gpu, "interleaved");
        let split_position = buffer("split_position")?;
        let split_normal = buffer("split_normal")?;
        // An estimate's buffer and images: `split_NAME`, `NAME`, and `seed_tmp`, `seed_out` with
        // `suffix` (none for the irradiance, `_specular` for `direct`'s).
        let estimate = |name: &str, suffix: &str| -> Result<Estimate> {
            Ok(Estimate {
                split: buffer(&format!("split_{name}"))?,
                gathered: img(name)?,
                seed: match seed {
                    Some(_) => Some((
                        img(&format!("seed_tmp{suffix}"))?,
                        img(&format!("seed_out{suffix}"))?,
                    )),
                    None => None,
                },
            })
        };
        let irradiance = estimate("irradiance", "")?;
        let specular = match config.direct {
            true => Some(estimate("specular", "_specular")?),
            false => None,
        };
        let mosaic = match mosaic_readback(config, w, h) {
            Some(rb) => Some(rb.make_readback(gpu, "readback")?),
            None => None,
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
        Ok(SplitPasses {
            split,
            implicit,
            seed,
            floor,
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
        scene: &GpuScene,
        g: &GBuffer,
        sources: &LightSources,
        count: u32,
        lights: [u32; 3],
        clamp_d2: f32,
    ) -> Result<()> {
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
        // Every resource by its binding name; each pass binds (and barriers) the ones it
        // declares.
        let binds = Binds::new()
            .image("position", &g.position)
            .image("normal", &g.normal);
        let mut binds = sources
            .bind(scene.bind_lights(binds))
            .image("irradiance", &im.irradiance.gathered);
        for (name, b) in [
            ("split_position", im.split_position.as_ref()),
            ("split_normal", im.split_normal.as_ref()),
            ("split_irradiance", im.irradiance.split.as_ref()),
            (
                "split_specular",
                im.specular.as_ref().and_then(|e| e.split.as_ref()),
            ),
        ] {
            if let Some(b) = b {
                binds = binds.buffer(name, b);
            }
        }
        if let Some(e) = &im.specular {
            binds = binds.image("specular", &e.gathered);
            if let Some((tmp, out)) = &e.seed {
                binds = binds
                    .image("seed_tmp_specular", tmp)
                    .image("seed_out_specular", out);
            }
        }
        if let Some((tmp, out)) = &im.irradiance.seed {
            binds = binds.image("seed_tmp", tmp).image("seed_out", out);
        }
        let [gx, gy, gz] = [full.0, full.1, full.2];
        if let Some(implicit) = &self.implicit {
            implicit.dispatch(cmd, profiler, &binds.only(implicit), &push, [gx, gy, gz])?;
        }
        if let Some((split, shade, gather)) = &self.split {
            split.dispatch(cmd, profiler, &binds.only(split), &push, [rows.0, sh, 1])?;
            let groups = [shade_groups.0, shade_groups.1, shade_groups.2];
            shade.dispatch(cmd, profiler, &binds.only(shade), &push, groups)?;
            let groups = [rows.0, rows.1, rows.2];
            gather.dispatch(cmd, profiler, &binds.only(gather), &push, groups)?;
        }
        if let Some((h, v)) = &self.seed {
            h.dispatch(cmd, profiler, &binds.only(h), &push, [gx, gy, gz])?;
            v.dispatch(cmd, profiler, &binds.only(v), &push, [gx, gy, gz])?;
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
}
