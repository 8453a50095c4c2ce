//! The scene on the GPU: geometry, materials and textures uploaded once; per-frame object
//! transforms, lights and constants rewritten each frame (camera-relative, computed in f64).

use cbr_gpu::{
    Buffer, Gpu, Image, ImageDesc, LevelCopy, Location, Result, Sampler, SamplerDesc, vk,
};
use cbr_scene::{AlphaSource, Camera, Scene};
use glam::{DMat3, DMat4, DVec3};

use crate::gpu_types::{
    FrameConstants, LightData, MAT_ALBEDO, MAT_ANISO_SHIFT, MAT_BUMP, MAT_MASK, MAX_PIECES,
    MaterialData, ObjectData, SplitBuffer,
};
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, Use};

/// The bindings of the scene's lights ([`GpuScene::bind_lights`]): the first
/// [`crate::gpu_types::UNIFORM_LIGHTS`] as a uniform buffer, the rest as a storage buffer.
pub const LIGHT_BINDINGS: [Binding; 2] = [
    Binding::uniform("lights"),
    Binding::buffer("more_lights", Use::Read),
];

/// One draw: an object's index range in the shared index buffer.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub object: u32,
    pub material: u32,
    pub first_index: u32,
    pub index_count: u32,
}

pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub materials: Buffer,
    pub textures: Vec<Image>,
    /// Bound in material slots without a texture.
    pub white: Image,
    /// Per material: the textures of its albedo, mask and bump slots.
    pub material_textures: Vec<[Option<u32>; 3]>,
    /// Per material: an alpha-tested one's coverage texture ([`cbr_scene::Texture::alpha_coverage`],
    /// after the scene's own in `textures`), which `analytic` binds in the mask slot.
    pub material_coverage: Vec<Option<u32>>,
    /// Per material: its texture paths (MAT_ALBEDO | MAT_MASK | MAT_BUMP; bump only with a
    /// height map and the scene's `bump` setting), from the material data the shaders read.
    pub material_features: Vec<u32>,
    pub sampler: Sampler,
    pub draws: Vec<Draw>,
    pub objects: Buffer,
    /// The scene's lights, directional first: the first [`crate::gpu_types::UNIFORM_LIGHTS`]
    /// bound as the uniform buffer `lights`, the rest as the storage buffer `more_lights`
    /// ([`GpuScene::bind_lights`]).
    pub lights: Buffer,
    pub frame: Buffer,
    pub light_count: (u32, u32),
    pub background: [f32; 3],
}

/// What the raster pass needs to know about its layout (scene_types.glsl's FrameConstants).
#[derive(Clone, Debug, Default)]
pub struct RasterUniforms {
    /// Size of the viewport that NDC maps to, in target pixels (jitters are scaled by it): the full
    /// resolution for native and masked, W/2 x H/2 for split and msaa2x, L x L for rotated.
    pub viewport: (f32, f32),
    /// Sub-pixel offsets of layers/instances 0 and 1, in target pixels.
    pub jitter: [[f32; 2]; 2],
    /// `counts.w` flags (FLAG_*).
    pub flags: u32,
    pub tangram: u32,
    pub pieces: Vec<[i32; 2]>,
}

/// The rotation (degrees per frame) at which an object's turn reaches 1.
pub const TURN_FULL_DEG: f64 = 10.0;

/// An object's turn this frame: the angle its own transform rotated since the previous frame
/// (the rotation of world · prev_world⁻¹, camera motion apart) over [`TURN_FULL_DEG`], capped
/// at one. A turning surface's normals turn with it, and its shading changes by as much from
/// frame to frame; a translating one's hardly does.
pub fn turn(world: &DMat4, prev_world: &DMat4) -> f32 {
    let r = DMat3::from_mat4(*world) * DMat3::from_mat4(*prev_world).inverse();
    let cos = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) * 0.5).clamp(-1.0, 1.0);
    let t = cos.acos().to_degrees() / TURN_FULL_DEG;
    if t.is_finite() {
        t.min(1.0) as f32
    } else {
        0.0
    }
}

/// Object IDs the reactive rules know the turn of (`turns` buffers, indexed by object ID; from
/// it on, 0).
pub const MAX_TURN_IDS: u32 = 4096;

/// Every object's [`turn`] between `prev_time` and `time`, by object ID (index + 1; 0 the
/// background, which does not turn).
pub fn object_turns(scene: &Scene, time: f64, prev_time: f64) -> Vec<f32> {
    std::iter::once(0.0)
        .chain((0..scene.objects.len()).map(|i| {
            turn(
                &scene.object_transform(i, time),
                &scene.object_transform(i, prev_time),
            )
        }))
        .collect()
}

/// Writes `turns` into a `turns` buffer of [`MAX_TURN_IDS`] floats (zeros past them).
pub fn write_turns(buffer: &mut Buffer, turns: &[f32]) -> Result<()> {
    let mut all = vec![0.0f32; MAX_TURN_IDS as usize];
    for (a, t) in all.iter_mut().zip(turns) {
        *a = *t;
    }
    buffer.write(0, bytemuck::cast_slice(&all))
}

/// Where the camera is for one frame, with its previous-frame state for velocities.
#[derive(Clone, Debug)]
pub struct FrameView {
    pub camera: Camera,
    pub prev_camera: Camera,
    pub time: f64,
    pub prev_time: f64,
    /// The resolution the pass renders at (velocity is in these pixels).
    pub width: u32,
    pub height: u32,
    /// Projection aspect: the output's W/H (equal to width/height except for `upscale`).
    pub aspect: f64,
    pub lod_bias: f32,
    /// (b, 1 / V): a fragment moving at speed s (pixels per frame) takes `lod_bias - b min(s /
    /// V, 1)` and is shaded min(s / V, 1) of the way back to the unjittered pixel centre
    /// (`+taa:unjitter`, b = 0; `+taa:motionlod`, b = TAA's bias): a moving pixel's history holds
    /// few samples to average a shifted, sharper sample over. (0, 0): the jittered raster, at
    /// the bias, everywhere.
    pub lod_motion: [f32; 2],
    /// The LOD bias a turning object's fragments withdraw in proportion to their object's turn
    /// ([`turn`]): a temporal technique's sharper bias (`taau`'s, `+taa`'s), which its history
    /// cannot average where the object's own rotation changes its shading every frame. 0: none.
    pub lod_turn: f32,
    /// The objects' turns reach the scene pass (ObjectData.ids.z; 0 otherwise): a technique or
    /// post pass of the frame applies a reactive rule. With `+taa`'s `unjitter` a turning
    /// object is then rasterised without the jitter by its turn (forward.vert).
    pub turns: bool,
    pub frame_index: u32,
    /// The projection's sub-pixel jitter in output pixels, every layout (RenderSettings::jitter
    /// plus a jittering post pass's).
    pub screen_jitter: [f32; 2],
    pub raster: RasterUniforms,
}

impl FrameView {
    /// This view rendered at `width` x `height` (`upscale`, `taau`): the same projection (the
    /// output's aspect), velocities and the raster's viewport in those pixels, the frame's raster
    /// flags kept and no layout mapping.
    pub fn at_size(&self, width: u32, height: u32) -> FrameView {
        FrameView {
            width,
            height,
            raster: RasterUniforms {
                viewport: (width as f32, height as f32),
                flags: self.raster.flags,
                ..Default::default()
            },
            ..self.clone()
        }
    }

    /// How far (pixels of this view) the background moved since the previous frame: the
    /// largest motion of a point at infinity seen at the frame's corners, edge midpoints and
    /// centre. The scene pass writes no velocity where it draws nothing (the background, whose
    /// depth is the clear value), and the background moves with the camera's rotation and field
    /// of view, not its position; a point behind the previous camera counts as infinitely far.
    pub fn background_motion(&self) -> f64 {
        let a = self.aspect;
        let focal = |c: &Camera| 1.0 / (c.fov_y_deg.to_radians() * 0.5).tan();
        let (f, fp) = (focal(&self.camera), focal(&self.prev_camera));
        let (r, rp) = (
            DMat3::from_mat4(self.camera.rotation()),
            DMat3::from_mat4(self.prev_camera.rotation()),
        );
        let size = glam::DVec2::new(f64::from(self.width), f64::from(self.height));
        let mut worst = 0.0f64;
        for (x, y) in [-1.0, 0.0, 1.0]
            .into_iter()
            .flat_map(|x| [-1.0, 0.0, 1.0].map(|y| (x, y)))
        {
            // NDC (x, y) to the view direction (z = -1; Camera::projection's y points down), to
            // the world, to the previous view, to its NDC.
            let world = r.transpose() * DVec3::new(x * a / f, -y / f, -1.0);
            let d = rp * world;
            if d.z >= 0.0 {
                return f64::INFINITY;
            }
            let prev = glam::DVec2::new(fp / a * d.x / -d.z, -fp * d.y / -d.z);
            let moved = (prev - glam::DVec2::new(x, y)) * 0.5 * size;
            worst = worst.max(moved.length());
        }
        worst
    }
}

fn to_f32(m: DMat4) -> [f32; 16] {
    m.as_mat4().to_cols_array()
}

fn material_data(m: &cbr_scene::Material, bump: bool) -> MaterialData {
    let tex = |t: Option<u32>| t.map(|t| t as i32).unwrap_or(-1);
    let (alpha_tex, channel) = match m.alpha {
        AlphaSource::Opaque => (-1, 0),
        AlphaSource::Texture { tex, channel } => (tex as i32, channel as i32),
    };
    // Height maps: a texel value of 1 is 1 cm of relief, times the MTL's -bm multiplier.
    let bump_height = 0.01 * m.bump_scale;
    MaterialData {
        kd: [m.kd[0], m.kd[1], m.kd[2], 0.0],
        ks: [
            m.ks[0],
            m.ks[1],
            m.ks[2],
            if m.ks.iter().any(|&k| k > 0.0) {
                m.ns
            } else {
                0.0
            },
        ],
        ke: [m.ke[0], m.ke[1], m.ke[2], bump_height],
        tex: [
            tex(m.kd_tex),
            alpha_tex,
            channel,
            if bump { tex(m.bump_tex) } else { -1 },
        ],
    }
}

/// Per material of `scene`, the texture paths its shading takes (MAT_ALBEDO, MAT_MASK,
/// MAT_BUMP) and, with any of them, the scene's anisotropy (MAT_ANISO_SHIFT): which raster
/// pipeline variant it draws with (crate::scene_pass::MaterialVariants), known without a device (the compile-only build's `PassCtx::materials`).
pub fn material_features(scene: &Scene) -> Vec<u32> {
    // The scene's anisotropy goes with every textured material's paths (bits 8-12); 1, the
    // isotropic default, is no bit, so those pipelines are the ones built before it existed.
    let aniso = match scene.settings.anisotropy {
        a @ 2.. => a.min(cbr_scene::MAX_ANISOTROPY) << MAT_ANISO_SHIFT,
        _ => 0,
    };
    scene
        .materials
        .iter()
        .map(|m| {
            // tex: albedo, mask, the mask's channel (no path of its own), bump; -1 = none.
            let paths = [MAT_ALBEDO, MAT_MASK, 0, MAT_BUMP]
                .iter()
                .zip(material_data(m, scene.settings.bump).tex)
                .filter(|&(_, t)| t >= 0)
                .fold(0, |f, (bit, _)| f | bit);
            if paths != 0 { paths | aniso } else { 0 }
        })
        .collect()
}

/// What an alpha-tested material's coverage texture is made of: its albedo texture, its mask
/// texture and the mask's channel.
type CoverageSource = (Option<u32>, u32, u32);

/// The alpha-tested materials' coverage textures ([`cbr_scene::Texture::alpha_coverage`]), one
/// per distinct source, and per material the index of its own in that list.
fn alpha_coverage_sources(scene: &Scene) -> (Vec<CoverageSource>, Vec<Option<u32>>) {
    let mut sources: Vec<CoverageSource> = Vec::new();
    let per_material = scene
        .materials
        .iter()
        .map(|m| match m.alpha {
            AlphaSource::Opaque => None,
            AlphaSource::Texture { tex, channel } => {
                let key = (m.kd_tex, tex, channel);
                let i = sources.iter().position(|&s| s == key).unwrap_or_else(|| {
                    sources.push(key);
                    sources.len() - 1
                });
                Some(i as u32)
            }
        })
        .collect();
    (sources, per_material)
}

fn alpha_coverage_texture(
    scene: &Scene,
    (albedo, mask, channel): CoverageSource,
) -> cbr_scene::Texture {
    cbr_scene::Texture::alpha_coverage(
        albedo.map(|a| &scene.textures[a as usize]),
        &scene.textures[mask as usize],
        channel as usize,
    )
}

/// Uploads the scene's textures, then `extra`, and, last, a 1x1 white one.
fn upload_textures(gpu: &Gpu, scene: &Scene, extra: &[cbr_scene::Texture]) -> Result<Vec<Image>> {
    let mut images = Vec::with_capacity(scene.textures.len() + extra.len() + 1);
    let mut staging_bytes = Vec::new();
    let mut copies: Vec<Vec<LevelCopy>> = Vec::new();
    let white = cbr_scene::Texture::from_rgba8("white", 1, 1, vec![255; 4], false);
    for (i, t) in scene
        .textures
        .iter()
        .chain(extra)
        .chain(std::iter::once(&white))
        .enumerate()
    {
        let format = if t.srgb {
            vk::Format::R8G8B8A8_SRGB
        } else {
            vk::Format::R8G8B8A8_UNORM
        };
        let name = format!("texture[{i}] {}", t.name);
        images.push(Image::new(
            gpu,
            &ImageDesc {
                name: &name,
                format,
                width: t.width(),
                height: t.height(),
                mip_levels: t.levels.len() as u32,
                layers: 1,
                samples: 1,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                flags: vk::ImageCreateFlags::empty(),
            },
        )?);
        let mut levels = Vec::new();
        for (l, level) in t.levels.iter().enumerate() {
            levels.push(LevelCopy {
                buffer_offset: staging_bytes.len() as u64,
                level: l as u32,
                width: level.width,
                height: level.height,
            });
            staging_bytes.extend_from_slice(&level.rgba);
        }
        copies.push(levels);
    }
    let mut staging = Buffer::new(
        gpu,
        "textures.staging",
        staging_bytes.len() as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        Location::CpuToGpu,
    )?;
    staging.write(0, &staging_bytes)?;
    gpu.submit("upload textures", |cmd| {
        for (img, levels) in images.iter().zip(&copies) {
            cmd.upload_levels(&staging, img, levels, cbr_gpu::Access::FragmentSampled);
        }
        Ok(())
    })?;
    Ok(images)
}

impl GpuScene {
    /// What [`GpuScene::new`] allocates for `scene`: vertices, indices and materials, every
    /// texture's mip chain and a 1x1 white one, the per-frame objects, lights and constants, and
    /// the largest of the uploads' staging buffers (each lives only through its own upload, so
    /// one of them at a time adds to the peak).
    pub fn estimate(scene: &Scene) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let vertices: usize = scene.objects.iter().map(|o| o.vertices.len()).sum();
        let indices: usize = scene.objects.iter().map(|o| o.indices.len()).sum();
        let uploads = [
            (
                "scene.vertices",
                vertices * std::mem::size_of::<cbr_scene::Vertex>(),
                true,
            ),
            ("scene.indices", indices * 4, false),
            (
                "scene.materials",
                scene.materials.len() * std::mem::size_of::<MaterialData>(),
                true,
            ),
        ];
        let mut staging = Vec::new();
        for (name, bytes, storage) in uploads {
            match storage {
                true => e.storage_buffer(name, bytes as u64, false),
                false => e.buffer(name, bytes as u64, false),
            }
            staging.push((format!("{name}.staging"), bytes as u64));
        }
        let mut texels = 0;
        for (i, t) in scene.textures.iter().enumerate() {
            let bytes = t.bytes();
            e.image_bytes(
                format!("texture[{i}] {}", t.name),
                bytes,
                t.width(),
                t.height(),
            );
            texels += bytes;
        }
        // The coverage textures have their source's size: the albedo's, else the mask's.
        let (sources, _) = alpha_coverage_sources(scene);
        for (k, &(albedo, mask, _)) in sources.iter().enumerate() {
            let (albedo, mask) = (
                albedo.map(|a| &scene.textures[a as usize]),
                &scene.textures[mask as usize],
            );
            let t = albedo.unwrap_or(mask);
            let bytes = t.bytes();
            let name = cbr_scene::Texture::alpha_coverage_name(albedo, mask);
            let i = scene.textures.len() + k;
            e.image_bytes(format!("texture[{i}] {name}"), bytes, t.width(), t.height());
            texels += bytes;
        }
        let white = scene.textures.len() + sources.len();
        e.image_bytes(format!("texture[{white}] white"), 4, 1, 1);
        staging.push(("textures.staging".into(), texels + 4));
        if let Some((name, bytes)) = staging.into_iter().max_by_key(|s| s.1) {
            e.buffer(name, bytes, true);
        }
        let objects = scene.objects.len().max(1) * std::mem::size_of::<ObjectData>();
        e.storage_buffer("scene.objects", objects as u64, true);
        let lights = (scene.directional.len() + scene.points.len()) as u64;
        e.storage_buffer("scene.lights", SplitBuffer::LIGHTS.bytes(lights), true);
        let frame = std::mem::size_of::<FrameConstants>() as u64;
        e.buffer("scene.frame", frame, true);
        e
    }

    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<GpuScene> {
        let mut vertex_bytes: Vec<u8> = Vec::new();
        let mut index_data: Vec<u32> = Vec::new();
        let mut draws = Vec::with_capacity(scene.objects.len());
        for (i, o) in scene.objects.iter().enumerate() {
            let base = (vertex_bytes.len() / std::mem::size_of::<cbr_scene::Vertex>()) as u32;
            draws.push(Draw {
                object: i as u32,
                material: o.material,
                first_index: index_data.len() as u32,
                index_count: o.indices.len() as u32,
            });
            vertex_bytes.extend_from_slice(bytemuck::cast_slice(&o.vertices));
            index_data.extend(o.indices.iter().map(|&k| k + base));
        }
        let usage_storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let vertices = Buffer::with_data(gpu, "scene.vertices", usage_storage, &vertex_bytes)?;
        let indices = Buffer::with_data(
            gpu,
            "scene.indices",
            vk::BufferUsageFlags::INDEX_BUFFER,
            bytemuck::cast_slice(&index_data),
        )?;
        let mats: Vec<MaterialData> = scene
            .materials
            .iter()
            .map(|m| material_data(m, scene.settings.bump))
            .collect();
        let materials = Buffer::with_data(
            gpu,
            "scene.materials",
            usage_storage,
            bytemuck::cast_slice(&mats),
        )?;
        let (coverage_sources, coverage_of) = alpha_coverage_sources(scene);
        let coverage: Vec<cbr_scene::Texture> = coverage_sources
            .iter()
            .map(|&src| alpha_coverage_texture(scene, src))
            .collect();
        let mut textures = upload_textures(gpu, scene, &coverage)?;
        let material_coverage = coverage_of
            .iter()
            .map(|c| c.map(|k| scene.textures.len() as u32 + k))
            .collect();
        let white = textures
            .pop()
            .ok_or_else(|| cbr_gpu::GpuError::Other("no white texture".into()))?;
        let material_textures = scene
            .materials
            .iter()
            .map(|m| {
                let mask = match m.alpha {
                    AlphaSource::Opaque => None,
                    AlphaSource::Texture { tex, .. } => Some(tex),
                };
                [m.kd_tex, mask, m.bump_tex]
            })
            .collect();
        let material_features = material_features(scene);
        let sampler = Sampler::new(
            gpu,
            "scene.sampler",
            SamplerDesc {
                linear: true,
                mipmaps: true,
                repeat: true,
                unnormalized: false,
            },
        )?;
        let objects = Buffer::new(
            gpu,
            "scene.objects",
            (scene.objects.len().max(1) * std::mem::size_of::<ObjectData>()) as u64,
            usage_storage,
            Location::CpuToGpu,
        )?;
        let light_count = (scene.directional.len() as u32, scene.points.len() as u32);
        let split = SplitBuffer::LIGHTS;
        split.check(gpu.caps(), &gpu.info().name, "the scene's lights")?;
        let lights = Buffer::new(
            gpu,
            "scene.lights",
            split.bytes((scene.directional.len() + scene.points.len()) as u64),
            usage_storage | vk::BufferUsageFlags::UNIFORM_BUFFER,
            Location::CpuToGpu,
        )?;
        let frame = Buffer::new(
            gpu,
            "scene.frame",
            std::mem::size_of::<FrameConstants>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            Location::CpuToGpu,
        )?;
        Ok(GpuScene {
            vertices,
            indices,
            materials,
            textures,
            white,
            material_textures,
            material_coverage,
            material_features,
            sampler,
            draws,
            objects,
            lights,
            frame,
            light_count,
            background: scene.settings.background,
        })
    }

    /// Binds the scene's lights: `lights` (uniform) and `more_lights` (storage).
    pub fn bind_lights<'a>(&'a self, binds: Binds<'a>) -> Binds<'a> {
        SplitBuffer::LIGHTS.bind(binds, &self.lights, "lights", "more_lights")
    }

    /// Writes this frame's transforms, lights and constants. Callers make sure no submission
    /// reading them is in flight (frames are submitted and waited on one at a time).
    pub fn update(&mut self, scene: &Scene, view: &FrameView) -> Result<()> {
        let aspect = view.aspect;
        let (cam, prev) = (&view.camera, &view.prev_camera);
        let clip_from_rel = cam.projection(aspect) * cam.rotation();
        let prev_clip_from_rel = prev.projection(aspect) * prev.rotation();
        let objects: Vec<ObjectData> = (0..scene.objects.len())
            .map(|i| {
                let world = scene.object_transform(i, view.time);
                let prev_world = scene.object_transform(i, view.prev_time);
                let rel = DMat4::from_translation(-cam.position) * world;
                let prev_rel = DMat4::from_translation(-prev.position) * prev_world;
                let normal = DMat4::from_mat3(DMat3::from_mat4(rel).inverse().transpose());
                ObjectData {
                    clip_from_local: to_f32(clip_from_rel * rel),
                    prev_clip_from_local: to_f32(prev_clip_from_rel * prev_rel),
                    world_from_local: to_f32(rel),
                    normal_from_local: to_f32(normal),
                    ids: [
                        i as u32 + 1,
                        scene.objects[i].material,
                        match view.turns {
                            true => turn(&world, &prev_world).to_bits(),
                            false => 0,
                        },
                        0,
                    ],
                }
            })
            .collect();
        self.objects.write(0, bytemuck::cast_slice(&objects))?;
        let mut lights: Vec<LightData> = scene
            .directional
            .iter()
            .map(|d| {
                let c = d.color.map(|c| c * d.intensity);
                LightData {
                    position: [d.direction[0], d.direction[1], d.direction[2], 0.0],
                    color: [c[0], c[1], c[2], 0.0],
                }
            })
            .collect();
        lights.extend(scene.points.iter().map(|p| {
            let rel = (DVec3::from(p.position) - cam.position).as_vec3();
            let c = p.color.map(|c| c * p.intensity);
            LightData {
                position: [rel.x, rel.y, rel.z, 1.0],
                color: [c[0], c[1], c[2], p.range],
            }
        }));
        if !lights.is_empty() {
            self.lights.write(0, bytemuck::cast_slice(&lights))?;
        }
        let a = scene.settings.ambient;
        let r = &view.raster;
        let (tw, th) = r.viewport;
        let (w, h) = (view.width as f32, view.height as f32);
        if r.pieces.len() > MAX_PIECES {
            return Err(cbr_gpu::GpuError::Other(format!(
                "{} tangram pieces; the constants hold {MAX_PIECES}",
                r.pieces.len()
            )));
        }
        let mut pieces = [[0i32; 4]; MAX_PIECES];
        for (dst, src) in pieces.iter_mut().zip(&r.pieces) {
            *dst = [src[0], src[1], 0, 0];
        }
        let constants = FrameConstants {
            viewport: [tw, th, 1.0 / tw, 1.0 / th],
            output_size: [w, h, 1.0 / w, 1.0 / h],
            jitter: [
                r.jitter[0][0],
                r.jitter[0][1],
                r.jitter[1][0],
                r.jitter[1][1],
            ],
            ambient: [a[0], a[1], a[2], view.lod_bias],
            counts: [
                self.light_count.0,
                self.light_count.1,
                view.frame_index,
                r.flags,
            ],
            tangram: [r.tangram as i32, r.pieces.len() as i32, 0, 0],
            screen_jitter: [
                view.screen_jitter[0],
                view.screen_jitter[1],
                view.lod_motion[0],
                view.lod_motion[1],
            ],
            turning: [view.lod_turn, 0.0, 0.0, 0.0],
            pieces,
        };
        self.frame.write(0, bytemuck::bytes_of(&constants))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An object's turn is its own rotation per frame over 10 degrees, at most 1, whatever its
    /// pivot and translation; a translating object does not turn.
    #[test]
    fn an_objects_turn_is_its_own_rotation() {
        let rot = |deg: f64| DMat4::from_rotation_y(deg.to_radians());
        let about = |deg: f64, pivot: DVec3| {
            DMat4::from_translation(pivot) * rot(deg) * DMat4::from_translation(-pivot)
        };
        let p = DVec3::new(3.0, 1.0, -2.0);
        let base = DMat4::from_translation(DVec3::new(0.5, 0.0, 1.0))
            * DMat4::from_scale(DVec3::splat(2.0));
        assert_eq!(turn(&base, &base), 0.0);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(
            turn(&(about(35.0, p) * base), &(about(30.0, p) * base)),
            0.5
        ));
        assert!(
            close(turn(&(about(-2.5, p) * base), &base), 0.25),
            "either direction"
        );
        assert_eq!(
            turn(&(about(48.0, p) * base), &(about(30.0, p) * base)),
            1.0
        );
        let moved = DMat4::from_translation(DVec3::new(4.0, 0.0, 0.0)) * base;
        assert_eq!(turn(&moved, &base), 0.0, "a translation");
        let x = DMat4::from_rotation_x(5f64.to_radians());
        assert!(close(turn(&(x * base), &base), 0.5), "about any axis");
    }

    fn view(camera: Camera, prev_camera: Camera) -> FrameView {
        FrameView {
            camera,
            prev_camera,
            time: 0.0,
            prev_time: 0.0,
            width: 320,
            height: 180,
            aspect: 320.0 / 180.0,
            lod_bias: 0.0,
            lod_motion: [0.0; 2],
            lod_turn: 0.0,
            turns: false,
            frame_index: 1,
            screen_jitter: [0.0; 2],
            raster: RasterUniforms::default(),
        }
    }

    fn cam(position: [f64; 3], target: [f64; 3]) -> Camera {
        Camera {
            position: DVec3::from(position),
            target: DVec3::from(target),
            fov_y_deg: 60.0,
            near: 0.1,
        }
    }

    /// The background (points at infinity) moves with the camera's rotation, not its position:
    /// 0 for a held or a translated camera; for a yaw of d, at least the centre's shift
    /// (W / 2) (f / aspect) tan(d) and at most the corners' (under 2.5 times it at 60 degrees);
    /// infinite where a point was behind the previous camera.
    #[test]
    fn the_background_moves_with_the_cameras_rotation_only() {
        let c = cam([0.0, 1.0, 0.0], [0.0, 1.0, -5.0]);
        assert_eq!(view(c, c).background_motion(), 0.0);
        let moved = cam([3.0, 2.0, 1.0], [3.0, 2.0, -4.0]);
        assert!(view(moved, c).background_motion() < 1e-9);
        let d = 0.01f64;
        let yawed = cam([0.0, 1.0, 0.0], [-5.0 * d.sin(), 1.0, -5.0 * d.cos()]);
        let f = 1.0 / 30f64.to_radians().tan();
        let centre = 160.0 * f / (320.0 / 180.0) * d.tan();
        let m = view(yawed, c).background_motion();
        assert!(
            m >= centre * 0.999 && m < 2.5 * centre,
            "{m} against {centre}"
        );
        let fov = Camera {
            fov_y_deg: 61.0,
            ..c
        };
        assert!(view(fov, c).background_motion() > 1.0);
        let back = cam([0.0, 1.0, 0.0], [0.0, 1.0, 5.0]);
        assert_eq!(view(back, c).background_motion(), f64::INFINITY);
    }
}
