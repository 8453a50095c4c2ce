//! What a pass declares it moves (cbr_gpu::Traffic, the input of `cbr gpu-stats`'s memory
//! model): the bytes of the bindings its compiled shader references, read or written as
//! declared, and its direct dispatches' invocations, taken per profiler scope. A binding the
//! shader does not reference in this variant moves nothing.

mod common;

use cbr_gpu::{Image, ImageDesc, Profiler, StaticTree, vk};
use cbr_render::pass::{Binding, Binds, ComputeDecl, Use};

const SHADER: &str = r#"#version 460
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
layout(set = 0, binding = BINDING_SRC) uniform sampler2D src;
layout(set = 0, binding = BINDING_EXTRA) uniform sampler2D extra;
layout(set = 0, binding = BINDING_DST, rgba16f) uniform writeonly image2D dst;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    vec4 v = texelFetch(src, p, 0);
#if USE_EXTRA
    v += texelFetch(extra, p, 0);
#endif
    imageStore(dst, p, v);
}
"#;

fn image(gpu: &cbr_gpu::Gpu, name: &str, w: u32, h: u32) -> Image {
    Image::new(
        gpu,
        &ImageDesc::new_2d(
            name,
            vk::Format::R16G16B16A16_SFLOAT,
            w,
            h,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::STORAGE,
        ),
    )
    .expect("image")
}

#[test]
fn a_scope_counts_the_referenced_bindings_bytes_and_its_invocations() {
    let gpu = common::gpu();
    let shaders = cbr_gpu::Shaders::new(Box::new(StaticTree(&[("t.comp", SHADER)])));
    let (w, h) = (40u32, 24u32);
    let (src, extra, dst) = (
        image(&gpu, "src", w, h),
        image(&gpu, "extra", w, h),
        image(&gpu, "dst", w, h),
    );
    // RGBA16F: 8 bytes a texel.
    let bytes = u64::from(w * h) * 8;
    for (use_extra, read) in [(0, bytes), (1, 2 * bytes)] {
        let pass = ComputeDecl::new("t", "t.comp")
            .define("USE_EXTRA", use_extra)
            .bindings(&[
                Binding::sampled("src"),
                Binding::sampled("extra"),
                Binding::image("dst", Use::Write),
            ])
            .group(8, 8)
            .build(&gpu, &shaders)
            .expect("pass");
        let mut profiler = Profiler::new(&gpu, "t.profiler", 4).expect("profiler");
        profiler.begin_frame();
        let binds = Binds::new()
            .image("src", &src)
            .image("extra", &extra)
            .image("dst", &dst);
        gpu.submit("t", |cmd| {
            pass.dispatch_2d(
                cmd,
                &mut profiler,
                &binds,
                &cbr_render::pass::NoPush {},
                (w, h),
            )
        })
        .expect("submit");
        let t = profiler.results().expect("results");
        assert_eq!(t.len(), 1);
        let t = t[0].traffic;
        assert_eq!(t.bytes_read, read, "USE_EXTRA={use_extra}: {t:?}");
        assert_eq!(t.bytes_written, bytes, "{t:?}");
        // 5 x 3 groups of 8 x 8.
        assert_eq!(t.compute_invocations, 5 * 3 * 64, "{t:?}");
        assert_eq!((t.dispatches, t.indirect_dispatches), (1, 0), "{t:?}");
    }
    common::assert_clean(&gpu);
}

#[test]
fn a_resolve_frame_traces_every_pass_with_its_traffic() {
    let gpu = common::gpu();
    let scene = common::demo(64, 36);
    let out = common::render_spec(&gpu, &scene, "checkerboard:rotated:pq4k", &[0, 1]);
    let f = &out[1];
    let resolve = f
        .timings
        .iter()
        .find(|t| t.name == "resolve")
        .expect("a resolve pass");
    // The default resolve: one 2x2 quad per invocation, groups of 8 x 8: 32 x 18 quads in
    // 4 x 3 groups of 64.
    assert_eq!(resolve.traffic.compute_invocations, 4 * 3 * 64);
    assert!(resolve.traffic.bytes_written >= 64 * 36 * 8, "{resolve:?}");
    let raster = f
        .timings
        .iter()
        .find(|t| t.traffic.render_passes > 0)
        .expect("a raster pass");
    assert!(raster.traffic.bytes_written > 0, "{raster:?}");
    assert!(
        raster.stats.is_some_and(|s| s.fragment_invocations > 0),
        "{raster:?}"
    );
    common::assert_clean(&gpu);
}
