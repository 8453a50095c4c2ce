//! `deferred`'s many-light sources on the GPU: the reflective shadow map (Dachsbacher &
//! Stamminger 2005) rendered from the sun (shaders/deferred/rsm.*), and the VPL generation pass
//! that turns the pattern's texels into virtual point lights (shaders/deferred/vpl.comp).

use bytemuck::{Pod, Zeroable};
use cbr_gpu::{
    Attachment, Buffer, Cmd, DescriptorSet, Gpu, GraphicsDesc, Image, ImageDesc, Location,
    PassKind, Pipeline, Profiler, Result, SetLayout, Shaders, vk,
};

use super::vpl::SunView;
use crate::gpu_scene::GpuScene;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, Use};
use crate::scene_pass::{self, LAYOUT_NATIVE, MATERIAL_BINDINGS};
use crate::targets::{DEPTH_FORMAT, GBUFFER_FORMAT};

/// Push constants of the RSM pass (shaders/deferred/rsm.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RsmPush {
    pub clip_from_world: [f32; 16],
    /// xyz: the sun's unit direction of travel; w: one texel's area (m^2).
    pub sun: [f32; 4],
    pub object_index: u32,
    pub pad: [u32; 3],
}

/// The map's layers: position, normal, flux (f32 RGBA) and reverse-Z depth.
pub struct RsmTargets {
    pub position: Image,
    pub normal: Image,
    pub flux: Image,
    pub depth: Image,
}

/// The reflective shadow map pass: the scene from the sun into a `side` x `side` map.
pub struct RsmPass {
    pipeline: Pipeline,
    _layouts: [SetLayout; 2],
    set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    pub targets: RsmTargets,
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
        let layout = SetLayout::new(gpu, "deferred.rsm.set_layout", &scene_pass::BINDINGS)?;
        let material_layout =
            SetLayout::new(gpu, "deferred.rsm.material_layout", &MATERIAL_BINDINGS)?;
        let defines = scene_pass::shader_defines(LAYOUT_NATIVE);
        let vs = shaders.compile("deferred/rsm.vert", &defines)?;
        let fs = shaders.compile("deferred/rsm.frag", &defines)?;
        let pipeline = Pipeline::graphics(
            gpu,
            &GraphicsDesc {
                name,
                vertex: &vs,
                geometry: None,
                fragment: &fs,
                set_layouts: &[&layout, &material_layout],
                push_constant_bytes: std::mem::size_of::<RsmPush>() as u32,
                color_formats: &[GBUFFER_FORMAT; 3],
                depth_format: Some(DEPTH_FORMAT),
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                samples: 1,
                min_sample_shading: None,
                cull_back_faces: false,
                sample_locations: false,
            },
        )?;
        let set = scene_pass::scene_set(gpu, name, &layout, scene, counter)?;
        let material_sets = scene_pass::material_sets(
            gpu,
            name,
            &material_layout,
            scene,
            scene_pass::MaskSlot::Mask,
        )?;
        let img = |n: &str, format, usage| {
            Image::new(
                gpu,
                &ImageDesc::new_2d(&format!("{name}.{n}"), format, side, side, usage),
            )
        };
        let color = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let targets = RsmTargets {
            position: img("position", GBUFFER_FORMAT, color)?,
            normal: img("normal", GBUFFER_FORMAT, color)?,
            flux: img("flux", GBUFFER_FORMAT, color)?,
            depth: img(
                "depth",
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            )?,
        };
        Ok(RsmPass {
            pipeline,
            _layouts: [layout, material_layout],
            set,
            material_sets,
            targets,
            side,
        })
    }

    /// Bytes of the map's four layers.
    pub fn bytes(&self) -> u64 {
        u64::from(self.side) * u64::from(self.side) * (3 * 16 + 4)
    }

    /// Clears the map (position w = 0: nothing seen) and draws every object from the sun;
    /// `None`: nothing is within reach, the map stays clear.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        sun: Option<&SunView>,
    ) {
        let scope = profiler.begin(cmd, "deferred.rsm", PassKind::Graphics);
        scene_pass::use_scene_buffers(cmd, scene);
        let t = &self.targets;
        let clear = |image| Attachment {
            image,
            clear: Some(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            }),
        };
        let depth = Attachment {
            image: &t.depth,
            clear: Some(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            }),
        };
        cmd.begin_rendering(
            &[clear(&t.position), clear(&t.normal), clear(&t.flux)],
            Some(depth),
            1,
        );
        if let Some(sun) = sun {
            self.draw(cmd, scene, sun);
        }
        cmd.end_rendering();
        profiler.end(cmd, scope);
    }

    fn draw(&self, cmd: &mut Cmd, scene: &GpuScene, sun: &SunView) {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        cmd.bind_index_buffer(&scene.indices);
        let d = sun.direction.as_vec3();
        let mut push = RsmPush {
            clip_from_world: sun.clip_from_world.as_mat4().to_cols_array(),
            sun: [d.x, d.y, d.z, sun.texel_area(self.side) as f32],
            ..RsmPush::default()
        };
        for draw in &scene.draws {
            cmd.bind_set(
                &self.pipeline,
                1,
                &self.material_sets[draw.material as usize],
            );
            push.object_index = draw.object;
            cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
            cmd.draw_indexed(draw.index_count, 1, draw.first_index, 0);
        }
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
            .image("rsm_position", &t.position)
            .image("rsm_normal", &t.normal)
            .image("rsm_flux", &t.flux)
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
