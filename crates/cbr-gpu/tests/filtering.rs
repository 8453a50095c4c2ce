//! How exactly the device's sampler interpolates between two texels. The CPU references of the
//! resolve, TAA and upscale passes model bilinear filtering with exact weights (the resolve's
//! Catmull-Rom runs as 5 bilinear taps), which is what lavapipe does for float formats although
//! it reports `subTexelPrecisionBits` 8. A GPU may quantise the weights to 2^-bits: the NVIDIA
//! driver's resolve differed from its CPU reference by 2.5e-3 to 3.9e-3 in the GPU study
//! (docs/resolve.md), the size that 8-bit weights give. This test measures it: a 2x1 RGBA16F
//! texture holding 0 and 1, sampled linearly at 4096 positions between the two texel centres,
//! must give the position's fraction; the distinct values and the worst deviation are printed.
//! Lavapipe must be exact (the references' assumption); any device within 2^-bits of it.

mod common;

use cbr_gpu::{
    Access, BindingDesc, Buffer, ComputeDesc, DescriptorKind, DescriptorSet, Image, ImageDesc,
    LevelCopy, Location, Pipeline, Readback, Sampler, SamplerDesc, SetLayout, Shaders, StaticTree,
    Write, vk,
};
use half::f16;

const N: u32 = 4096;

const KERNEL: &str = r#"#version 460
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform sampler2D ramp;
layout(std430, set = 0, binding = 1) writeonly buffer Out { float v[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    // Unnormalised coordinates: texel 0's centre at 0.5, texel 1's at 1.5.
    float t = float(i) / 4096.0;
    v[i] = textureLod(ramp, vec2(0.5 + t, 0.5), 0.0).r;
}
"#;

static TREE: [(&str, &str); 1] = [("ramp.comp", KERNEL)];

#[test]
fn linear_filtering_weights_are_measured() {
    let gpu = common::gpu();
    let shaders = Shaders::new(Box::new(StaticTree(&TREE)));
    let cs = shaders.compile("ramp.comp", &[]).expect("compile");
    let bindings = [
        BindingDesc::one("ramp", 0, DescriptorKind::CombinedImageSampler),
        BindingDesc::one("out", 1, DescriptorKind::StorageBuffer),
    ];
    let layout = SetLayout::new(&gpu, "ramp.layout", &bindings).expect("layout");
    let pipeline = Pipeline::compute(
        &gpu,
        &ComputeDesc {
            name: "ramp",
            shader: &cs,
            set_layouts: &[&layout],
            push_constant_bytes: 0,
        },
    )
    .expect("pipeline");
    let image = Image::new(
        &gpu,
        &ImageDesc::new_2d(
            "ramp.image",
            vk::Format::R16G16B16A16_SFLOAT,
            2,
            1,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        ),
    )
    .expect("image");
    let texels: Vec<u16> = [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0]
        .iter()
        .map(|&x| f16::from_f32(x).to_bits())
        .collect();
    let mut staging = Buffer::new(
        &gpu,
        "ramp.staging",
        16,
        vk::BufferUsageFlags::TRANSFER_SRC,
        Location::CpuToGpu,
    )
    .expect("staging");
    staging
        .write(0, bytemuck::cast_slice(&texels))
        .expect("write");
    let sampler = Sampler::new(
        &gpu,
        "ramp.sampler",
        SamplerDesc {
            linear: true,
            mipmaps: false,
            repeat: false,
            unnormalized: true,
        },
    )
    .expect("sampler");
    let out = Buffer::new(
        &gpu,
        "ramp.out",
        4 * u64::from(N),
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
        Location::GpuOnly,
    )
    .expect("out");
    let rb = Readback::for_buffer(&gpu, "ramp.readback", 4 * u64::from(N), N, 1).expect("rb");
    let set = DescriptorSet::new(
        &gpu,
        "ramp.set",
        &layout,
        &[
            Write::Sampled(0, vec![(&image, &sampler)]),
            Write::Buffer(1, &out),
        ],
    )
    .expect("set");
    gpu.submit("ramp", |cmd| {
        cmd.upload_levels(
            &staging,
            &image,
            &[LevelCopy {
                buffer_offset: 0,
                level: 0,
                width: 2,
                height: 1,
            }],
            Access::ComputeSampled,
        );
        cmd.use_buffer(&out, Access::ComputeStorageWrite);
        cmd.bind_pipeline(&pipeline);
        cmd.bind_set(&pipeline, 0, &set);
        cmd.dispatch(N / 64, 1, 1);
        cmd.read_buffer(&out, &rb);
        Ok(())
    })
    .expect("submit");
    let v: &[f32] = bytemuck::cast_slice(rb.bytes().expect("bytes"));
    let worst = v
        .iter()
        .enumerate()
        .map(|(i, &x)| (f64::from(x) - i as f64 / f64::from(N)).abs())
        .fold(0.0f64, f64::max);
    let mut levels: Vec<u32> = v.iter().map(|x| x.to_bits()).collect();
    levels.dedup();
    let bits = gpu.caps().sub_texel_precision_bits;
    println!(
        "{} ({}): linear filtering between two texels: {} distinct values over {N} positions, \
         worst deviation from the exact weight {worst:.3e} (subTexelPrecisionBits {bits}: 2^-bits \
         = {:.3e})",
        gpu.info().name,
        gpu.info().driver_name,
        levels.len(),
        0.5f64.powi(bits as i32)
    );
    if gpu.info().driver_name == "llvmpipe" {
        assert!(
            worst <= 1e-6,
            "lavapipe's weights are not exact ({worst:e}): the CPU references assume they are"
        );
    }
    assert!(worst <= 0.5f64.powi(bits as i32), "{worst:e}");
    assert!(
        gpu.validation().messages().is_empty(),
        "{:?}",
        gpu.validation().messages()
    );
}
