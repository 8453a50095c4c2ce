//! The registered techniques, one module each, and what several of them share: reading the four
//! common layers back, and the layers several write (`mask`, the prepass's, `coverage`).

/// Declares each technique's module and lists its registration: adding a technique is its
/// module, its shader folder and its name in the one list below.
macro_rules! techniques {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*
        /// Every technique, in the order `cbr render --help` and errors list them.
        pub const TECHNIQUES: &[crate::technique::Registration] = &[$($m::REGISTRATION),*];
    };
}

techniques!(
    native,
    ssaa,
    msaa,
    checkerboard,
    upscale,
    taau,
    interlaced,
    analytic,
    deferred,
    interleaved,
    flicker,
);

use cbr_gpu::{Buffer, Cmd, Gpu, Image, PassKind, Profiler, Readback, Result, Shaders};
use half::f16;

use crate::frame::{ExrType, FrameOutput, Layer, LayerDecl, SampleType};
use crate::gpu_scene::GpuScene;
use crate::memory::MemoryEstimate;
use crate::pass::{Binds, ResourceDecl};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};

/// A native-resolution depth + ID pass at the pixel centres, no shading: checkerboard's
/// `prepass`, and the depth and IDs of `msaa` (whose multisampled targets hold no IDs).
pub struct IdPass {
    pass: ScenePass,
    config: RasterConfig,
    pub ids: Image,
    pub depth: Image,
    pub ids_rb: Readback,
    pub depth_rb: Readback,
}

impl IdPass {
    const NAME: &str = "id_prepass.raster";

    /// Native's raster, depth and IDs only.
    fn raster(w: u32, h: u32) -> RasterConfig {
        RasterConfig {
            id_only: true,
            ..RasterConfig::native(w, h)
        }
    }

    /// Its raster pipelines, for the compile-only list.
    pub fn decls(
        ctx: &crate::technique::PassCtx,
    ) -> std::result::Result<Vec<crate::pass::GraphicsDecl>, String> {
        crate::scene_pass::listed(
            Self::NAME,
            &Self::raster(ctx.width, ctx.height),
            ctx.materials,
        )
    }

    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &GpuScene,
        w: u32,
        h: u32,
        counter: &Buffer,
    ) -> Result<IdPass> {
        let config = Self::raster(w, h);
        let pass = ScenePass::new(gpu, shaders, scene, Self::NAME, &config, counter)?;
        let [ids, depth, ids_rb, depth_rb] = Self::resources(w, h);
        let (ids, depth) = (
            ids.make_image(gpu, "id_prepass")?,
            depth.make_image(gpu, "id_prepass")?,
        );
        let ids_rb = ids_rb.make_readback(gpu, "readback")?;
        let depth_rb = depth_rb.make_readback(gpu, "readback")?;
        Ok(IdPass {
            pass,
            config,
            ids,
            depth,
            ids_rb,
            depth_rb,
        })
    }

    /// Its ID and depth targets (native's) and their readbacks (`readback.prepass_*`).
    fn resources(w: u32, h: u32) -> [ResourceDecl; 4] {
        let [_, _, ids, depth] = FrameTargets::decls(w, h, 1, 1, false);
        [
            ids,
            depth,
            ResourceDecl::readback("prepass_ids", ID_FORMAT, w, h),
            ResourceDecl::readback("prepass_depth", DEPTH_FORMAT, w, h),
        ]
    }

    /// What [`IdPass::new`] allocates.
    pub fn estimate(e: &mut MemoryEstimate, w: u32, h: u32) {
        let [ids, depth, ids_rb, depth_rb] = Self::resources(w, h);
        e.append(crate::pass::estimate(&[ids, depth], "id_prepass"));
        e.append(crate::pass::estimate(&[ids_rb, depth_rb], "readback"));
    }

    /// Records the raster and the copies of its IDs and depth.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        counter: &Buffer,
    ) -> Result<()> {
        let targets = Binds::new()
            .image("ids", &self.ids)
            .image("depth", &self.depth);
        self.pass
            .record(cmd, profiler, scene, &targets, counter, &self.config)?;
        cmd.read_image(&self.ids, &self.ids_rb);
        cmd.read_image(&self.depth, &self.depth_rb);
        Ok(())
    }

    /// View depths (+inf where empty) and IDs.
    pub fn output(&self, near: f64) -> Result<(Vec<f32>, Vec<[u32; 2]>)> {
        Ok((
            linear_depths(bytemuck::cast_slice(self.depth_rb.bytes()?), near),
            bytemuck::cast_slice::<u8, [u32; 2]>(self.ids_rb.bytes()?).to_vec(),
        ))
    }

    /// The frame's [`PREPASS_LAYERS`] from [`IdPass::output`].
    pub fn layers(&self, w: u32, h: u32, near: f64) -> Result<Vec<Layer>> {
        let (depth, ids) = self.output(near)?;
        let [d, o, p] = &PREPASS_LAYERS;
        Ok(vec![
            d.layer(w, h, vec![depth])?,
            o.layer(w, h, vec![ids.iter().map(|i| i[0]).collect()])?,
            p.layer(w, h, vec![ids.iter().map(|i| i[1]).collect()])?,
        ])
    }

    /// A frame's prepass outputs (view depths, IDs), when it has them.
    pub fn from_frame(out: &FrameOutput) -> Option<(Vec<f32>, Vec<[u32; 2]>)> {
        let depth = out.channel::<f32>("prepass_depth", "Z")?;
        let object = out.channel::<u32>("prepass_object_id", "id")?;
        let primitive = out.channel::<u32>("prepass_primitive_id", "id")?;
        let ids = object
            .iter()
            .zip(primitive)
            .map(|(&o, &p)| [o, p])
            .collect();
        Some((depth.to_vec(), ids))
    }
}

/// `mask`: 1 where this frame shaded the pixel (checkerboard, interlaced).
pub const MASK_LAYER: LayerDecl = LayerDecl {
    name: "mask",
    channels: &["Y"],
    samples: SampleType::U8,
    exr: Some(ExrType::Half),
    about: "1 where this frame shaded the pixel",
};

/// A frame's [`MASK_LAYER`].
pub fn mask(out: &FrameOutput) -> Option<&[u8]> {
    out.channel("mask", "Y")
}

/// The native-resolution depth + ID prepass ([`IdPass`]): view depth (+inf where empty), object
/// and primitive IDs.
pub const PREPASS_LAYERS: [LayerDecl; 3] = [
    LayerDecl {
        name: "prepass_depth",
        channels: &["Z"],
        samples: SampleType::F32,
        exr: Some(ExrType::Float),
        about: "the ID prepass's view depth (+inf where empty)",
    },
    LayerDecl {
        name: "prepass_object_id",
        channels: &["id"],
        samples: SampleType::U32,
        exr: Some(ExrType::Uint),
        about: "the ID prepass's object IDs",
    },
    LayerDecl {
        name: "prepass_primitive_id",
        channels: &["id"],
        samples: SampleType::U32,
        exr: Some(ExrType::Uint),
        about: "the ID prepass's primitive IDs",
    },
];

/// `coverage` (supersampled and analytic frames): `edge`, 1 where the pixel's samples saw more
/// than one object ID (background counts as one), and `fraction`, of the samples on geometry.
pub const COVERAGE_LAYER: LayerDecl = LayerDecl {
    name: "coverage",
    channels: &["edge", "fraction"],
    samples: SampleType::F32,
    exr: Some(ExrType::Float),
    about: "edge: 1 where the pixel's samples saw several object IDs; fraction: of the samples \
            on geometry",
};

/// The [`COVERAGE_LAYER`] of supersampled (`ssaa`) and `analytic` frames, typed.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// 1 where the pixel's samples saw more than one object ID (background counts as one).
    pub edge: Vec<u8>,
    /// Fraction of the pixel's samples that hit geometry.
    pub fraction: Vec<f32>,
}

impl Coverage {
    /// A frame's coverage, when it has the layer.
    pub fn from_frame(out: &FrameOutput) -> Option<Coverage> {
        let edge = out.channel::<f32>("coverage", "edge")?;
        Some(Coverage {
            edge: edge.iter().map(|&e| u8::from(e != 0.0)).collect(),
            fraction: out.channel::<f32>("coverage", "fraction")?.to_vec(),
        })
    }

    /// The layer of this coverage at `w` x `h`.
    pub fn layer(&self, w: u32, h: u32) -> Result<Layer> {
        let edge = self.edge.iter().map(|&e| f32::from(e)).collect();
        COVERAGE_LAYER.layer(w, h, vec![edge, self.fraction.clone()])
    }
}

/// Readbacks of full-resolution colour (RGBA16F), reverse-Z depth (D32 or R32F), velocity and
/// IDs: the common layers of every technique that ends in four images.
pub struct LayerReadbacks {
    color: Readback,
    depth: Readback,
    velocity: Readback,
    ids: Readback,
}

impl LayerReadbacks {
    /// The four readbacks of `width` x `height` layers (depth D32 or R32F: 4 bytes either way).
    pub fn decls(width: u32, height: u32) -> [ResourceDecl; 4] {
        [
            ResourceDecl::readback("color", COLOR_FORMAT, width, height),
            ResourceDecl::readback("depth", DEPTH_FORMAT, width, height),
            ResourceDecl::readback("velocity", VELOCITY_FORMAT, width, height),
            ResourceDecl::readback("ids", ID_FORMAT, width, height),
        ]
    }

    /// The readbacks of `images` (colour, depth, velocity, IDs: [`LayerReadbacks::record`]'s
    /// order), at the colour's size.
    pub fn new(gpu: &Gpu, images: [&Image; 4]) -> Result<LayerReadbacks> {
        let [color, depth, velocity, ids] =
            LayerReadbacks::decls(images[0].width, images[0].height);
        Ok(LayerReadbacks {
            color: color.make_readback(gpu, "readback")?,
            depth: depth.make_readback(gpu, "readback")?,
            velocity: velocity.make_readback(gpu, "readback")?,
            ids: ids.make_readback(gpu, "readback")?,
        })
    }

    /// What [`LayerReadbacks::new`] allocates for `width` x `height` layers.
    pub fn estimate(e: &mut MemoryEstimate, width: u32, height: u32) {
        e.append(crate::pass::estimate(
            &LayerReadbacks::decls(width, height),
            "readback",
        ));
    }

    /// Records the copies (timed as `readback`).
    pub fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler, images: [&Image; 4]) {
        let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
        cmd.read_image(images[0], &self.color);
        cmd.read_image(images[1], &self.depth);
        cmd.read_image(images[2], &self.velocity);
        cmd.read_image(images[3], &self.ids);
        profiler.end(cmd, scope);
    }

    /// The frame from the copies; reverse-Z depth becomes view distance (`near / d`).
    pub fn output(&self, width: u32, height: u32, near: f64) -> Result<FrameOutput> {
        Ok(FrameOutput::new(
            width,
            height,
            bytemuck::cast_slice::<u8, f16>(self.color.bytes()?).to_vec(),
            linear_depths(bytemuck::cast_slice(self.depth.bytes()?), near),
            bytemuck::cast_slice::<u8, [f32; 2]>(self.velocity.bytes()?).to_vec(),
            bytemuck::cast_slice::<u8, [u32; 2]>(self.ids.bytes()?).to_vec(),
        ))
    }
}

/// Reverse-Z depths (infinite far plane) as view distances; +inf where nothing was drawn.
pub fn linear_depths(reverse_z: &[f32], near: f64) -> Vec<f32> {
    let near = near as f32;
    reverse_z
        .iter()
        .map(|&d| if d > 0.0 { near / d } else { f32::INFINITY })
        .collect()
}

/// Parameters of a technique that takes none.
pub fn no_params(name: &str, params: &[&str]) -> std::result::Result<(), String> {
    match params.first() {
        None => Ok(()),
        Some(p) => Err(crate::technique::unknown_param(name, p, "no parameters")),
    }
}
