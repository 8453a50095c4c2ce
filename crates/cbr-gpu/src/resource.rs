//! RAII buffers, images and samplers. Dropping one hands it to the deletion queue, which destroys
//! it once the GPU has finished every submission recorded before the drop.

use std::cell::Cell;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

use crate::access::Access;
use crate::context::{Garbage, Gpu, Inner};
use crate::error::{GpuError, Result, VkContext};

pub use gpu_allocator::MemoryLocation as Location;

fn allocate(
    gpu: &Gpu,
    name: &str,
    req: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> Result<Allocation> {
    let mut guard = gpu
        .inner
        .allocator
        .lock()
        .map_err(|_| GpuError::Other("allocator lock poisoned".into()))?;
    let al = guard
        .as_mut()
        .ok_or_else(|| GpuError::Other("allocator already destroyed".into()))?;
    let a = al
        .allocate(&AllocationCreateDesc {
            name,
            requirements: req,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })
        .map_err(|e| GpuError::Alloc {
            name: name.to_string(),
            source: e,
        })?;
    gpu.inner
        .allocations_made
        .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    Ok(a)
}

/// A named buffer with its memory.
pub struct Buffer {
    gpu: Arc<Inner>,
    raw: vk::Buffer,
    alloc: Option<Allocation>,
    size: u64,
    pub(crate) last: Cell<Access>,
}

impl Buffer {
    pub fn new(
        gpu: &Gpu,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        gpu.require_execution(&format!("the buffer `{name}`"))?;
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let dev = gpu.device();
        // SAFETY: valid create info.
        let raw = unsafe { dev.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` was just created.
        let req = unsafe { dev.get_buffer_memory_requirements(raw) };
        let alloc = match allocate(gpu, name, req, location, true) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unused, never bound.
                unsafe { dev.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: memory from the allocator satisfies `req`.
        unsafe { dev.bind_buffer_memory(raw, alloc.memory(), alloc.offset()) }
            .vk("vkBindBufferMemory")?;
        gpu.name_object(raw, name);
        Ok(Buffer {
            gpu: gpu.inner.clone(),
            raw,
            alloc: Some(alloc),
            size,
            last: Cell::new(Access::Undefined),
        })
    }

    /// A device-local buffer holding `data`, uploaded through a staging buffer.
    pub fn with_data(
        gpu: &Gpu,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[u8],
    ) -> Result<Buffer> {
        let buf = Buffer::new(
            gpu,
            name,
            data.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        if data.is_empty() {
            return Ok(buf);
        }
        let mut staging = Buffer::new(
            gpu,
            &format!("{name}.staging"),
            data.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.write(0, data)?;
        gpu.submit(&format!("upload {name}"), |cmd| {
            cmd.copy_buffer(&staging, &buf, data.len() as u64);
            Ok(())
        })?;
        Ok(buf)
    }

    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }
    /// Host-visible (mapped) memory: a readback or upload buffer.
    pub fn host_visible(&self) -> bool {
        self.alloc
            .as_ref()
            .is_some_and(|a| a.mapped_ptr().is_some())
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    /// Host-visible contents (for `CpuToGpu`/`GpuToCpu` buffers): the buffer's `size` bytes. The
    /// allocation's mapped slice is as long as the memory requirements, which a driver may round
    /// up (NVIDIA's did: tests/readback.rs).
    pub fn bytes(&self) -> Result<&[u8]> {
        let size = self.size as usize;
        self.alloc
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .and_then(|s| s.get(..size))
            .ok_or_else(|| GpuError::Other("buffer is not host visible".into()))
    }

    /// Writes `data` at `offset` of a host-visible buffer.
    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<()> {
        let size = self.size;
        let dst = self
            .alloc
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| GpuError::Other("buffer is not host visible".into()))?;
        let n = (size as usize).min(dst.len());
        let dst = &mut dst[..n];
        let end = offset + data.len();
        if end > dst.len() {
            return Err(GpuError::Other(format!(
                "write of {end} bytes past a {}-byte buffer",
                dst.len()
            )));
        }
        dst[offset..end].copy_from_slice(data);
        Ok(())
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.alloc.take() {
            self.gpu.defer(Garbage::Buffer(self.raw, a));
        }
    }
}

/// What an image is.
#[derive(Clone, Debug)]
pub struct ImageDesc<'a> {
    pub name: &'a str,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub mip_levels: u32,
    pub layers: u32,
    pub samples: u32,
    pub usage: vk::ImageUsageFlags,
    /// Creation flags (e.g. SAMPLE_LOCATIONS_COMPATIBLE_DEPTH_EXT for msaa2x's alternative).
    pub flags: vk::ImageCreateFlags,
}

impl<'a> ImageDesc<'a> {
    /// A single-level, single-layer, single-sample 2D image.
    pub fn new_2d(
        name: &'a str,
        format: vk::Format,
        width: u32,
        height: u32,
        usage: vk::ImageUsageFlags,
    ) -> Self {
        ImageDesc {
            name,
            format,
            width,
            height,
            mip_levels: 1,
            layers: 1,
            samples: 1,
            usage,
            flags: vk::ImageCreateFlags::empty(),
        }
    }
}

/// A named image with one view over all its levels and layers.
pub struct Image {
    gpu: Arc<Inner>,
    raw: vk::Image,
    view: vk::ImageView,
    alloc: Option<Allocation>,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub mip_levels: u32,
    pub layers: u32,
    pub samples: u32,
    pub(crate) last: Cell<Access>,
    /// The custom sample locations last rendered with (depth images created sample-locations
    /// compatible): chained into this image's layout transitions.
    pub(crate) sample_locations: Cell<Option<[[f32; 2]; 2]>>,
}

pub fn is_depth_format(f: vk::Format) -> bool {
    matches!(
        f,
        vk::Format::D32_SFLOAT
            | vk::Format::D16_UNORM
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
    )
}

/// Bytes per texel of the formats cbr reads back or uploads.
pub fn texel_size(f: vk::Format) -> Option<usize> {
    use vk::Format as F;
    Some(match f {
        F::R8_UNORM | F::R8_UINT => 1,
        F::R8G8B8A8_UNORM
        | F::R8G8B8A8_SRGB
        | F::R32_SFLOAT
        | F::R32_UINT
        | F::D32_SFLOAT
        | F::R16G16_SFLOAT => 4,
        F::R16G16B16A16_SFLOAT | F::R32G32_SFLOAT | F::R32G32_UINT => 8,
        F::R32G32B32A32_SFLOAT | F::R32G32B32A32_UINT => 16,
        _ => return None,
    })
}

impl Image {
    /// Bytes of level 0, every layer and sample ([`texel_size`]; a format it does not list
    /// counts 16 bytes a texel, never under-counted).
    pub fn traffic_bytes(&self) -> u64 {
        let texel = texel_size(self.format).map_or(16, |t| t as u64);
        u64::from(self.width)
            * u64::from(self.height)
            * u64::from(self.layers)
            * u64::from(self.samples)
            * texel
    }

    pub fn new(gpu: &Gpu, d: &ImageDesc) -> Result<Image> {
        // Before vkCreateImage: RADV's null device crashes in it.
        gpu.require_execution(&format!("the image `{}`", d.name))?;
        let max = gpu.caps().max_image_dimension_2d;
        if d.width == 0 || d.height == 0 || d.width > max || d.height > max {
            return Err(GpuError::Unsupported {
                device: gpu.info().name.clone(),
                feature: format!(
                    "a {}x{} image `{}` (limit {max}x{max})",
                    d.width, d.height, d.name
                ),
            });
        }
        let info = vk::ImageCreateInfo::default()
            .flags(d.flags)
            .image_type(vk::ImageType::TYPE_2D)
            .format(d.format)
            .extent(vk::Extent3D {
                width: d.width,
                height: d.height,
                depth: 1,
            })
            .mip_levels(d.mip_levels)
            .array_layers(d.layers)
            .samples(vk::SampleCountFlags::from_raw(d.samples))
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(d.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let dev = gpu.device();
        // SAFETY: valid create info; size checked against the device limit.
        let raw = unsafe { dev.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: `raw` was just created.
        let req = unsafe { dev.get_image_memory_requirements(raw) };
        let alloc = match allocate(gpu, d.name, req, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unused.
                unsafe { dev.destroy_image(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: memory satisfies `req`.
        unsafe { dev.bind_image_memory(raw, alloc.memory(), alloc.offset()) }
            .vk("vkBindImageMemory")?;
        let aspect = aspect_of(d.format);
        let vinfo = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(if d.layers > 1 {
                vk::ImageViewType::TYPE_2D_ARRAY
            } else {
                vk::ImageViewType::TYPE_2D
            })
            .format(d.format)
            .subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(aspect)
                    .level_count(d.mip_levels)
                    .layer_count(d.layers),
            );
        // SAFETY: the image is bound to memory.
        let view = unsafe { dev.create_image_view(&vinfo, None) }.vk("vkCreateImageView")?;
        gpu.name_object(raw, d.name);
        gpu.name_object(view, &format!("{}.view", d.name));
        Ok(Image {
            gpu: gpu.inner.clone(),
            raw,
            view,
            alloc: Some(alloc),
            format: d.format,
            width: d.width,
            height: d.height,
            mip_levels: d.mip_levels,
            layers: d.layers,
            samples: d.samples,
            last: Cell::new(Access::Undefined),
            sample_locations: Cell::new(None),
        })
    }

    pub fn raw(&self) -> vk::Image {
        self.raw
    }
    pub fn view(&self) -> vk::ImageView {
        self.view
    }
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.format)
    }
    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D {
            width: self.width,
            height: self.height,
        }
    }
    /// Bytes of one full-resolution layer of level 0.
    pub fn level0_bytes(&self) -> Result<usize> {
        let t = texel_size(self.format)
            .ok_or_else(|| GpuError::Other(format!("no texel size for {:?}", self.format)))?;
        Ok(self.width as usize * self.height as usize * t)
    }
}

pub(crate) fn aspect_of(f: vk::Format) -> vk::ImageAspectFlags {
    if is_depth_format(f) {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        if let Some(a) = self.alloc.take() {
            self.gpu.defer(Garbage::Image(self.raw, vec![self.view], a));
        }
    }
}

/// Sampler settings cbr uses.
#[derive(Clone, Copy, Debug)]
pub struct SamplerDesc {
    pub linear: bool,
    pub mipmaps: bool,
    pub repeat: bool,
    /// Texel-unit coordinates (texel i's centre at i + 0.5; Vulkan's unnormalizedCoordinates):
    /// positions computed in pixels reach the sampler without a division and its rounding, so a
    /// position on a texel centre filters to that texel exactly. Needs clamp to edge, no mips,
    /// and `textureLod(.., 0)` in the shader.
    pub unnormalized: bool,
}

impl SamplerDesc {
    /// Nearest, no mips, clamp to edge: for texelFetch-style reads of render targets.
    pub const NEAREST: SamplerDesc = SamplerDesc {
        linear: false,
        mipmaps: false,
        repeat: false,
        unnormalized: false,
    };
}

pub struct Sampler {
    gpu: Arc<Inner>,
    raw: vk::Sampler,
}

impl Sampler {
    pub fn new(gpu: &Gpu, name: &str, d: SamplerDesc) -> Result<Sampler> {
        let filter = if d.linear {
            vk::Filter::LINEAR
        } else {
            vk::Filter::NEAREST
        };
        let mode = if d.repeat {
            vk::SamplerAddressMode::REPEAT
        } else {
            vk::SamplerAddressMode::CLAMP_TO_EDGE
        };
        debug_assert!(!d.unnormalized || (!d.repeat && !d.mipmaps));
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(if d.linear && !d.unnormalized {
                vk::SamplerMipmapMode::LINEAR
            } else {
                vk::SamplerMipmapMode::NEAREST
            })
            .address_mode_u(mode)
            .address_mode_v(mode)
            .address_mode_w(mode)
            .unnormalized_coordinates(d.unnormalized)
            .min_lod(0.0)
            .max_lod(if d.mipmaps { vk::LOD_CLAMP_NONE } else { 0.0 });
        // SAFETY: valid create info.
        let raw = unsafe { gpu.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        gpu.name_object(raw, name);
        Ok(Sampler {
            gpu: gpu.inner.clone(),
            raw,
        })
    }
    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        self.gpu.defer(Garbage::Sampler(self.raw));
    }
}

/// A host-visible buffer an image is copied into, read after the submission completes.
pub struct Readback {
    pub(crate) buffer: Buffer,
    pub width: u32,
    pub height: u32,
}

impl Readback {
    pub fn for_image(gpu: &Gpu, name: &str, image: &Image) -> Result<Readback> {
        let bytes = image.level0_bytes()? * image.layers as usize;
        let buffer = Buffer::new(
            gpu,
            name,
            bytes as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        Ok(Readback {
            buffer,
            width: image.width,
            height: image.height,
        })
    }

    /// A readback of `bytes` bytes of a buffer holding `width` x `height` texels
    /// ([`crate::Cmd::read_buffer`]).
    pub fn for_buffer(
        gpu: &Gpu,
        name: &str,
        bytes: u64,
        width: u32,
        height: u32,
    ) -> Result<Readback> {
        let buffer = Buffer::new(
            gpu,
            name,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        Ok(Readback {
            buffer,
            width,
            height,
        })
    }

    /// The image's texels, rows top to bottom, tightly packed (layers one after another).
    pub fn bytes(&self) -> Result<&[u8]> {
        self.buffer.bytes()
    }
}
