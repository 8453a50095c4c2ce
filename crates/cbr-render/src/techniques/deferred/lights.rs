//! The many lights of `deferred` (and of `interleaved`, which shades the same ones): the
//! `points=N` random point lights, and with `vpls=N` the sun's reflective shadow map, the VPL pass
//! and the VPL buffer, prepared on the host and recorded each frame.

use cbr_gpu::{Access, Buffer, Cmd, GpuError, Profiler, Result, vk};
use cbr_scene::PointLight;
use glam::DVec3;

use super::config::DeferredConfig;
use super::lighting::{LightSources, SunFrame};
use super::rsm::{RsmPass, VplPass};
use super::vpl::{self, SunView};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::{SplitBuffer, Vpl};
use crate::pass::{Memory, ResourceDecl};
use crate::technique::{BuildCtx, FrameCtx};

/// The light buffers (under the technique's name): the `points=N` lights, written by the host
/// each frame, and the VPLs (device-local, written by the VPL pass). Each is read through two
/// views, its first part as a uniform buffer and the rest as a storage buffer ([`SplitBuffer`]),
/// so each is at least its uniform part long, whatever the count.
pub fn resources(config: &DeferredConfig) -> [ResourceDecl; 2] {
    let uniform = vk::BufferUsageFlags::UNIFORM_BUFFER;
    [
        ResourceDecl::buffer_in(
            "points",
            SplitBuffer::LIGHTS.bytes(u64::from(config.points)),
            vk::BufferUsageFlags::STORAGE_BUFFER | uniform,
            Memory::Upload,
        ),
        ResourceDecl::buffer_in(
            "vpls",
            SplitBuffer::VPLS.bytes(u64::from(config.vpls)),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | uniform,
            Memory::Device,
        ),
    ]
}

fn vpl_bytes(config: &DeferredConfig) -> u64 {
    u64::from(config.vpls.max(1)) * std::mem::size_of::<Vpl>() as u64
}

/// With VPLs: their readback (`readback.vpls`).
pub fn vpl_readback(config: &DeferredConfig) -> ResourceDecl {
    ResourceDecl::readback_buffer("vpls", vpl_bytes(config))
}

pub struct ManyLights {
    config: DeferredConfig,
    /// The `points=N` lights (world), drawn at the first frame from the scene's seed.
    point_lights: Option<Vec<PointLight>>,
    points: Buffer,
    rsm: Option<RsmPass>,
    vpl_pass: Option<VplPass>,
    /// The VPLs (device-local; one unread VPL when there are none), read by the lighting pass.
    vpls: Buffer,
    vpl_readback: Option<Buffer>,
    /// The scene seed the VPL pattern was written for.
    texels_seed: Option<u64>,
    local_bounds: Option<Vec<Option<(DVec3, DVec3)>>>,
}

impl ManyLights {
    /// The buffers and passes `config` asks for; refused when it asks for VPLs and the scene has
    /// no sun. `name` prefixes the objects' debug names (and the refusal).
    pub fn new(ctx: &BuildCtx, config: &DeferredConfig, name: &str) -> Result<ManyLights> {
        if config.vpls > 0 && ctx.scene.light_count.0 == 0 {
            return Err(GpuError::Other(format!(
                "{name}:vpls={}: the VPLs come from a reflective shadow map rendered from the \
                 sun, the scene's first directional light, and this scene has none (use vpls=0; \
                 points=N adds point lights)",
                config.vpls
            )));
        }
        let gpu = ctx.gpu;
        let device = &gpu.info().name;
        let (caps, what) = (gpu.caps(), |w: &str| format!("{name}'s {w}"));
        SplitBuffer::LIGHTS.check(caps, device, &what("point lights"))?;
        SplitBuffer::VPLS.check(caps, device, &what("VPLs"))?;
        let [points, vpls] = resources(config);
        let (points, vpls) = (points.make_buffer(gpu, name)?, vpls.make_buffer(gpu, name)?);
        let (rsm, vpl_pass, vpl_readback) = if config.vpls > 0 {
            let rsm = RsmPass::new(gpu, ctx.shaders, ctx.scene, ctx.counter, config.rsm)?;
            let vp = VplPass::new(gpu, ctx.shaders, &rsm, config.vpls)?;
            let rb = vpl_readback(config).make_buffer(gpu, "readback")?;
            (Some(rsm), Some(vp), Some(rb))
        } else {
            (None, None, None)
        };
        Ok(ManyLights {
            config: *config,
            point_lights: None,
            points,
            rsm,
            vpl_pass,
            vpls,
            vpl_readback,
            texels_seed: None,
            local_bounds: None,
        })
    }

    pub fn sources(&self) -> LightSources<'_> {
        LightSources {
            points: &self.points,
            vpls: &self.vpls,
        }
    }

    /// Writes this frame's extra point lights and, with VPLs, the pattern (once per seed);
    /// returns where the sun's map looks and the VPL clamp (`None`: no VPLs).
    pub fn prepare(&mut self, ctx: &FrameCtx) -> Result<Option<SunFrame>> {
        let scene = ctx.scene;
        let camera = ctx.view.camera.position;
        let reach = f64::from(self.config.reach);
        if self.config.points > 0 {
            let lights = self
                .point_lights
                .get_or_insert_with(|| vpl::random_point_lights(scene, self.config.points, reach));
            let data = vpl::light_data(lights, camera);
            self.points.write(0, bytemuck::cast_slice(&data))?;
        }
        let Some(vp) = self.vpl_pass.as_mut() else {
            return Ok(None);
        };
        let (n, side) = (self.config.vpls, self.config.rsm);
        let seed = scene.settings.seed;
        if self.texels_seed != Some(seed) {
            vp.write_texels(&vpl::vpl_texels(seed, n, side))?;
            self.texels_seed = Some(seed);
        }
        let sun = scene
            .directional
            .first()
            .ok_or_else(|| GpuError::Other("the VPLs need a directional light (the sun)".into()))?;
        let local = self
            .local_bounds
            .get_or_insert_with(|| vpl::local_bounds(scene));
        let bounds = vpl::bounds_at(scene, local, ctx.view.time);
        let view = match vpl::framed_region(bounds, camera, reach) {
            Some(region) => {
                Some(SunView::new(sun.direction, region, camera, side).map_err(GpuError::Other)?)
            }
            None => None,
        };
        let clamp_d2 = match (self.config.clamp, &view) {
            (Some(d), _) => d * d,
            // The VPLs' mean spacing: the map's area over N.
            (None, Some(v)) => (4.0 * v.radius * v.radius / f64::from(n)) as f32,
            (None, None) => 1.0,
        };
        Ok(Some(SunFrame { view, clamp_d2 }))
    }

    /// The map and the VPL pass, with VPLs.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        sun: Option<&SunFrame>,
    ) -> Result<()> {
        if let (Some(rsm), Some(vp), Some(sun)) = (&self.rsm, &self.vpl_pass, sun) {
            rsm.record(cmd, profiler, scene, sun.view.as_ref())?;
            vp.record(cmd, profiler, rsm, &self.vpls)?;
        }
        Ok(())
    }

    /// The VPLs' copy for the host, with VPLs (after the passes that read them).
    pub fn record_readback(&self, cmd: &mut Cmd) {
        if let Some(rb) = &self.vpl_readback {
            cmd.copy_buffer(&self.vpls, rb, rb.size());
            cmd.use_buffer(rb, Access::HostRead);
        }
    }

    /// This frame's VPLs, with VPLs.
    pub fn read_vpls(&self) -> Result<Option<Vec<Vpl>>> {
        let Some(rb) = &self.vpl_readback else {
            return Ok(None);
        };
        let n = self.config.vpls as usize * std::mem::size_of::<Vpl>();
        Ok(Some(bytemuck::pod_collect_to_vec(&rb.bytes()?[..n])))
    }

    /// Bytes of the map.
    pub fn bytes(&self) -> u64 {
        self.rsm.as_ref().map_or(0, RsmPass::bytes)
    }
}
