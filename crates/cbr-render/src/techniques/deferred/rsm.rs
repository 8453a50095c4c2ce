//! `deferred`'s many-light sources on the GPU: the reflective shadow map (Dachsbacher &
//! Stamminger 2005) rendered from the sun (shaders/deferred/rsm.*), and the VPL generation pass
//! that turns the pattern's texels into virtual point lights (shaders/deferred/vpl.comp).

use cbr_gpu::{
    Attachment, Buffer, Cmd, DescriptorSet, Gpu, Location, PassKind, Profiler, Result, Shaders, vk,
};

use super::vpl::SunView;
use crate::gpu_scene::GpuScene;
use crate::pass::{
    Binding, Binds, ComputeDecl, ComputePass, GraphicsDecl, GraphicsPass, ResourceDecl, Resources,
    Use,
};
use crate::scene_pass::{self, LAYOUT_NATIVE, MATERIAL_SET, SCENE_SET};
use crate::targets::{DEPTH_FORMAT, GBUFFER_FORMAT};

crate::push_constants! {
    /// Push constants of the RSM pass (shaders/deferred/rsm.glsl).
    pub struct RsmPush {
        clip_from_world: [[f32; 4]; 4],
        /// xyz: the sun's unit direction of travel; w: one texel's area (m^2).
        sun: [f32; 4],
        object_index: u32,
    }
}

/// The map's layers: position, normal, flux (f32 RGBA) and reverse-Z depth, `side` x `side`.
pub fn resources(side: u32) -> Vec<ResourceDecl> {
    let mut r: Vec<ResourceDecl> = ["position", "normal", "flux"]
        .into_iter()
        .map(|n| ResourceDecl::attachment(n, GBUFFER_FORMAT, side, side, 1))
        .collect();
    r.push(ResourceDecl::attachment(
        "depth",
        DEPTH_FORMAT,
        side,
        side,
        1,
    ));
    r
}

/// The RSM raster: the scene's sets, its push constants, the map's layers as attachments.
pub fn decl() -> GraphicsDecl {
    GraphicsDecl::new("deferred.rsm", "deferred/rsm.vert", "deferred/rsm.frag")
        .shared(SCENE_SET)
        .shared(MATERIAL_SET)
        .push::<RsmPush>()
        .define("LAYOUT", LAYOUT_NATIVE)
        .color("position", GBUFFER_FORMAT)
        .color("normal", GBUFFER_FORMAT)
        .color("flux", GBUFFER_FORMAT)
        .depth("depth", DEPTH_FORMAT)
}

/// The reflective shadow map pass: the scene from the sun into a `side` x `side` map.
pub struct RsmPass {
    pass: GraphicsPass,
    set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    /// The map's layers ([`resources`]).
    pub targets: Resources,
    pub side: u32,
}

impl RsmPass {
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &GpuScene,
        counter: &Buffer,
        side: u32,
    ) -> Result<RsmPass> {
        let name = "deferred.rsm";
        let pass = decl().build(gpu, shaders)?;
        let set = SCENE_SET.make(
            gpu,
            name,
            pass.layout("scene")?,
            &scene_pass::scene_binds(scene, counter),
        )?;
        let material_sets = scene_pass::material_sets(
            gpu,
            name,
            pass.layout("material")?,
            scene,
            scene_pass::MaskSlot::Mask,
        )?;
        let targets = Resources::new(gpu, name, &resources(side))?;
        Ok(RsmPass {
            pass,
            set,
            material_sets,
            targets,
            side,
        })
    }

    /// Bytes of the map's four layers.
    pub fn bytes(&self) -> u64 {
        crate::pass::estimate(&resources(self.side), "deferred.rsm").total()
    }

    /// Clears the map (position w = 0: nothing seen) and draws every object from the sun;
    /// `None`: nothing is within reach, the map stays clear.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        sun: Option<&SunView>,
    ) -> Result<()> {
        let binds = Binds::of(&self.targets).shared(&SCENE_SET, &self.set);
        let (colors, depth) = self.pass.attachments(&binds)?;
        self.pass.prepare(cmd, &binds)?;
        let scope = profiler.begin(cmd, "deferred.rsm", PassKind::Graphics);
        scene_pass::use_scene_buffers(cmd, scene);
        let clear = |image| Attachment {
            image,
            clear: Some(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            }),
        };
        let depth = depth.map(|image| Attachment {
            image,
            clear: Some(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            }),
        });
        let colors: Vec<Attachment> = colors.into_iter().map(clear).collect();
        cmd.begin_rendering(&colors, depth, 1);
        if let Some(sun) = sun {
            self.pass.bind(cmd, &binds)?;
            self.draw(cmd, scene, sun)?;
        }
        cmd.end_rendering();
        profiler.end(cmd, scope);
        Ok(())
    }

    fn draw(&self, cmd: &mut Cmd, scene: &GpuScene, sun: &SunView) -> Result<()> {
        let pipeline = self.pass.pipeline();
        let material = self.pass.set_index("material")?;
        cmd.bind_index_buffer(&scene.indices);
        let d = sun.direction.as_vec3();
        let mut push = RsmPush {
            clip_from_world: sun.clip_from_world.as_mat4().to_cols_array_2d(),
            sun: [d.x, d.y, d.z, sun.texel_area(self.side) as f32],
            ..RsmPush::default()
        };
        for draw in &scene.draws {
            cmd.bind_set(
                pipeline,
                material,
                &self.material_sets[draw.material as usize],
            );
            push.object_index = draw.object;
            cmd.push_constants(pipeline, bytemuck::bytes_of(&push));
            cmd.draw_indexed(draw.index_count, 1, draw.first_index, 0);
        }
        Ok(())
    }
}

crate::push_constants! {
    struct VplPush {
        count: u32,
        /// Texels per VPL: each VPL carries that many texels' flux.
        share: f32,
    }
}

/// The VPL generation pass (shaders/deferred/vpl.comp).
pub fn vpl_decl() -> ComputeDecl {
    ComputeDecl::new("deferred.vpls", "deferred/vpl.comp")
        .bindings(&[
            Binding::sampled("rsm_position"),
            Binding::sampled("rsm_normal"),
            Binding::sampled("rsm_flux"),
            Binding::buffer("texels", Use::Read),
            Binding::buffer("vpls", Use::Write),
        ])
        .push::<VplPush>()
        .group(64, 1)
}

/// VPLs from the map: VPL i is texel `texels[i]` with `texels / count` times its flux.
pub struct VplPass {
    pass: ComputePass,
    /// The pattern's texels (host-written once per scene seed).
    pub texels: Buffer,
    pub count: u32,
    share: f32,
}

impl VplPass {
    /// VPLs (at least `count` x 48 bytes) from `rsm`.
    pub fn new(gpu: &Gpu, shaders: &Shaders, rsm: &RsmPass, count: u32) -> Result<VplPass> {
        let n = u64::from(count.max(1));
        let texels = Buffer::new(
            gpu,
            "deferred.vpl_texels",
            n * 8,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            Location::CpuToGpu,
        )?;
        let texel_count = f64::from(rsm.side) * f64::from(rsm.side);
        Ok(VplPass {
            pass: vpl_decl().build(gpu, shaders)?,
            texels,
            count,
            share: (texel_count / f64::from(count.max(1))) as f32,
        })
    }

    /// Writes the pattern's texels (no submission in flight may read them).
    pub fn write_texels(&mut self, texels: &[[u32; 2]]) -> Result<()> {
        self.texels.write(0, bytemuck::cast_slice(texels))
    }

    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        rsm: &RsmPass,
        vpls: &Buffer,
    ) -> Result<()> {
        let t = &rsm.targets;
        let binds = Binds::new()
            .image("rsm_position", t.image("position")?)
            .image("rsm_normal", t.image("normal")?)
            .image("rsm_flux", t.image("flux")?)
            .buffer("texels", &self.texels)
            .buffer("vpls", vpls);
        let push = VplPush {
            count: self.count,
            share: self.share,
        };
        let groups = [self.count.div_ceil(64), 1, 1];
        self.pass.dispatch(cmd, profiler, &binds, &push, groups)
    }
}
