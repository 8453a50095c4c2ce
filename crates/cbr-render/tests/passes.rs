//! Passes declared once (crate::pass): the declared passes build their pipelines without a
//! single allocation (the compile-only build), with zero validation messages; binds that do not
//! fit the declaration are errors, not panics.

mod common;

use cbr_gpu::{GpuError, Image, ImageDesc, Layout, vk};
use cbr_render::checkerboard::unpack;
use cbr_render::layouts::LayoutPlan;
use cbr_render::pass::{Binding, Binds, ComputeDecl, ResourceDecl, Resources, Use};
use cbr_render::post::{fxaa, sharpen, taa};
use cbr_render::resolve::{self, Mapping, ResolveMode, ResolveSettings};
use cbr_render::taau;
use cbr_render::techniques::analytic;
use cbr_render::techniques::deferred;
use cbr_render::techniques::interlaced::{self, InterlacedSettings};
use cbr_render::techniques::msaa::{self, MsaaConfig};
use cbr_render::techniques::ssaa;
use cbr_render::upscale::{self, UpscaleFilter};

/// Every pass declared through crate::pass so far, with every variant its parameters select.
fn declared() -> Vec<ComputeDecl> {
    let mut d = vec![sharpen::decl(), ssaa::decl()];
    d.extend(fxaa::decls());
    // TAA: ours with each history kernel, and INSIDE's.
    for params in [
        &[][..],
        &["without-lanczos"],
        &["without-catmull"],
        &["inside"],
    ] {
        let c = taa::TaaConfig::parse(params).expect("taa");
        for packed in [false, true] {
            d.push(taa::decl(&c, packed));
        }
    }
    // The resolve: every mode, pixel and quad, groups 8 and 16, with and without the prepass.
    let plan = LayoutPlan::new(Layout::Rotated, 64, 36, 0);
    for mode in ResolveMode::ALL {
        for mapping in [Mapping::Pixel, Mapping::Quad] {
            for group in [8, 16] {
                let s = ResolveSettings {
                    mode,
                    mapping,
                    group,
                    ..ResolveSettings::default()
                };
                d.push(resolve::decl(&s, &plan, group == 16));
            }
        }
    }
    d.push(resolve::copy_floor_decl("resolve.copy_floor"));
    // The unpack of every portable layout, upscale's filters (FSR 1's two passes), msaa's two
    // resolves.
    for layout in [Layout::Masked, Layout::Split, Layout::Rotated] {
        d.push(unpack::decl(&LayoutPlan::new(layout, 64, 36, 1)));
    }
    d.extend(UpscaleFilter::ALL.into_iter().flat_map(upscale::decls));
    for spec in [
        &[][..],
        &["bilinear", "without-stability", "debug"],
        &["catmull"],
    ] {
        d.extend(taau::decls(&taau::parse(spec).expect("taau")));
    }
    for debug in [false, true] {
        d.push(interlaced::resolve::decl(&InterlacedSettings {
            debug,
            ..InterlacedSettings::default()
        }));
    }
    d.push(deferred::lighting::decl(None));
    d.push(deferred::rsm::vpl_decl());
    for hdr in [false, true] {
        d.push(msaa::decl(MsaaConfig {
            hdr,
            ..msaa::parse(&["4"]).expect("msaa:4")
        }));
    }
    // analytic's five passes with each mask size, the seed, the box and the anisotropic filter
    // (lavapipe's 128 MiB storage-buffer range).
    for params in [
        &[][..],
        &["samples=32", "aniso"],
        &["samples=128", "seed", "frags=3"],
    ] {
        let c = analytic::parse(params).expect("analytic");
        let k = analytic::Kernel::new(c, 64, 36, 1 << 27).expect("fits");
        d.extend(analytic::decls(&k));
    }
    d
}

#[test]
fn declared_passes_build_without_allocating() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let before = gpu.allocations_made();
    let built: Vec<_> = declared()
        .iter()
        .map(|d| {
            d.build(&gpu, &shaders)
                .unwrap_or_else(|e| panic!("{}: {e}", d.name))
        })
        .collect();
    assert_eq!(built.len(), 76);
    assert_eq!(
        gpu.allocations_made(),
        before,
        "a compile-only build allocated memory"
    );
    common::assert_clean(&gpu);
}

/// Every raster pipeline the scene pass and the RSM declare, over every material variant.
fn declared_rasters() -> Vec<cbr_render::pass::GraphicsDecl> {
    use cbr_render::scene_pass::{self, RasterConfig};
    let native = RasterConfig::native(64, 36);
    let configs = [
        native.clone(),
        RasterConfig {
            gbuffer: true,
            depth_prepass: true,
            ..native.clone()
        },
        RasterConfig {
            id_only: true,
            ..native.clone()
        },
        RasterConfig {
            samples: 4,
            write_ids: false,
            sample_shading: true,
            ..native.clone()
        },
        RasterConfig::for_plan(&LayoutPlan::new(Layout::Rotated, 64, 36, 0)),
        RasterConfig::for_plan(&LayoutPlan::new(Layout::Split, 64, 36, 1)),
    ];
    // No texture, albedo + bump (the G-buffer's late-test path) and every path: each shader path
    // is compiled at least once (all eight combinations are what the scene's materials pick).
    let features = [0, 1 | 4, 1 | 2 | 4];
    let mut d = vec![deferred::rsm::decl()];
    for (i, c) in configs.iter().enumerate() {
        d.extend(scene_pass::decls(&format!("raster{i}"), c, &features).expect("declared"));
    }
    // analytic's select and raster passes, with the seed and the anisotropic filter.
    let c = cbr_render::techniques::analytic::parse(&["seed", "aniso"]).expect("analytic");
    let k = cbr_render::techniques::analytic::Kernel::new(c, 64, 36, 1 << 27).expect("fits");
    d.extend(cbr_render::techniques::analytic::raster_decls(
        &k, &features,
    ));
    d
}

#[test]
fn declared_rasters_build_without_allocating() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let before = gpu.allocations_made();
    let decls = declared_rasters();
    for d in &decls {
        d.build(&gpu, &shaders)
            .unwrap_or_else(|e| panic!("{}: {e}", d.name));
    }
    // 6 configurations x 3 variants, the G-buffer's with a depth pre-pass and (2 bump-mapped
    // variants) late tests, the RSM, and analytic's select and raster x 3 variants.
    assert_eq!(decls.len(), 6 * 3 + 3 + 2 + 1 + 2 * 3);
    assert_eq!(
        gpu.allocations_made(),
        before,
        "a compile-only build allocated memory"
    );
    common::assert_clean(&gpu);
}

/// A raster pass's attachments are bound by name and checked against their declared formats;
/// a name it does not declare is an error.
#[test]
fn raster_attachments_are_checked_by_name_and_format() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let pass = deferred::rsm::decl().build(&gpu, &shaders).expect("rsm");
    let make = |name, format, usage| {
        Image::new(&gpu, &ImageDesc::new_2d(name, format, 8, 8, usage)).expect("image")
    };
    let color = vk::ImageUsageFlags::COLOR_ATTACHMENT;
    let f32x4 = make("t.f32x4", vk::Format::R32G32B32A32_SFLOAT, color);
    let f16x4 = make("t.f16x4", vk::Format::R16G16B16A16_SFLOAT, color);
    let depth = make(
        "t.depth",
        vk::Format::D32_SFLOAT,
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
    );
    let good = Binds::new()
        .image("position", &f32x4)
        .image("normal", &f32x4)
        .image("flux", &f32x4)
        .image("depth", &depth);
    let (colors, d) = pass.attachments(&good).expect("attachments");
    assert_eq!((colors.len(), d.is_some()), (3, true));
    let message = |r: cbr_gpu::Result<_>| match r {
        Err(GpuError::Declaration { message, .. }) => message,
        Err(e) => panic!("expected a declaration error, got {e}"),
        Ok(_) => panic!("expected a declaration error"),
    };
    let wrong = message(pass.attachments(&good.clone().image("flux", &f16x4)));
    assert!(wrong.contains("attachment `flux`"), "{wrong}");
    let missing = message(pass.attachments(&Binds::new().image("position", &f32x4)));
    assert!(
        missing.contains("no image bound to attachment `normal`"),
        "{missing}"
    );
    let misspelt = good.clone().image("flx", &f32x4);
    let misspelt = gpu
        .submit("t.misspelt", |cmd| pass.prepare(cmd, &misspelt))
        .expect_err("misspelt");
    assert!(
        misspelt
            .to_string()
            .contains("`flx` is bound but not declared"),
        "{misspelt}"
    );
    common::assert_clean(&gpu);
}

#[test]
fn binds_that_do_not_fit_the_declaration_are_errors() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let pass = sharpen::decl().build(&gpu, &shaders).expect("sharpen");
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let img = |name| {
        Image::new(
            &gpu,
            &ImageDesc::new_2d(name, vk::Format::R16G16B16A16_SFLOAT, 8, 8, usage),
        )
        .expect("image")
    };
    let (a, b) = (img("t.a"), img("t.b"));
    let counter = cbr_gpu::Buffer::new(
        &gpu,
        "t.buffer",
        16,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        cbr_gpu::Location::GpuOnly,
    )
    .expect("buffer");
    let declaration = |r: cbr_gpu::Result<()>| match r {
        Err(GpuError::Declaration { pass, message }) => format!("{pass}: {message}"),
        other => panic!("expected a declaration error, got {other:?}"),
    };
    assert!(
        pass.check(&Binds::new().image("src", &a).image("out", &b))
            .is_ok()
    );
    let missing = declaration(pass.check(&Binds::new().image("src", &a)));
    assert!(missing.contains("nothing bound to `out`"), "{missing}");
    let wrong = declaration(pass.check(&Binds::new().image("src", &a).buffer("out", &counter)));
    assert!(
        wrong.contains("`out` is a storage image, given a buffer"),
        "{wrong}"
    );
    let misspelt = Binds::new()
        .image("src", &a)
        .image("out", &b)
        .image("outt", &b);
    let misspelt = declaration(pass.check(&misspelt));
    assert!(
        misspelt.contains("`outt` is bound but not declared"),
        "{misspelt}"
    );
    // A binding of a given sampler takes an image with its sampler (analytic's albedo pass: a scene texture
    // through the scene's sampler), and a plain image is refused.
    let k = analytic::Kernel::new(analytic::parse(&[]).expect("analytic"), 8, 8, 1 << 27)
        .expect("fits");
    let albedo = analytic::albedo_decl(&k)
        .build(&gpu, &shaders)
        .expect("albedo");
    let sampler =
        cbr_gpu::Sampler::new(&gpu, "t.sampler", cbr_gpu::SamplerDesc::NEAREST).expect("sampler");
    let buffers = [
        "albedo_jobs",
        "albedo_bins",
        "albedo_order",
        "colors",
        "cells",
        "cells_hi",
        "tail_records",
        "frame",
        "materials",
    ]
    .into_iter()
    .fold(Binds::new(), |b, name| b.buffer(name, &counter));
    assert!(
        albedo
            .check(&buffers.clone().sampled("albedo_texture", &a, &sampler))
            .is_ok()
    );
    let untextured = declaration(albedo.check(&buffers.clone().image("albedo_texture", &a)));
    assert!(
        untextured
            .contains("`albedo_texture` is a sampled image with a given sampler, given an image"),
        "{untextured}"
    );
    let textured =
        declaration(pass.check(&Binds::new().sampled("src", &a, &sampler).image("out", &b)));
    assert!(
        textured.contains("`src` is a sampled image, given an image with its sampler"),
        "{textured}"
    );
    // A declaration naming a binding twice is refused when it is built.
    let twice = ComputeDecl::new("twice", "post/sharpen.comp")
        .bind(Binding::sampled("src"))
        .bind(Binding::image("src", Use::Write));
    assert!(matches!(
        twice.build(&gpu, &shaders),
        Err(GpuError::Declaration { .. })
    ));
    common::assert_clean(&gpu);
}

/// The compile-only list of a spec (`registry::passes`) is exactly the compute shaders, with
/// their defines, that building the spec's renderer compiles: rendering and the compile-only
/// build use one list.
#[test]
fn the_compile_only_list_is_what_rendering_builds() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let scene = common::demo(64, 36);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    let ctx = common::pass_ctx(&gpu, &materials, false);
    let specs = [
        "native",
        "ssaa:2",
        "msaa:4",
        "msaa:4:hdr",
        "checkerboard:rotated:ours",
        "checkerboard:split:pq4k:prepass",
        "checkerboard:masked:none",
        "checkerboard:rotated:ours:pixel:16+taa",
        "upscale:bicubic+fxaa",
        "upscale:fsr1:0.77+taa",
        "taau",
        "taau:0.5:bilinear:without-locks:without-depth-clip:without-rcas:debug",
        "taau:catmull:without-stability+fxaa",
        "interlaced:debug",
        "deferred",
        "deferred:vpls=64",
        "native+taa:inside+sharpen",
        "interleaved:4x4",
        "interleaved:4x4:vpls=64:implicit",
        "interleaved:2x2:seed:direct:debug",
        "interleaved:4x4:box:direct",
        "interleaved:4x4:floor",
        "analytic",
        "analytic:seed:frags=3:samples=32",
        "analytic:aniso:samples=128",
    ];
    // And every registered technique by its bare name where that is a spec (a new technique is
    // held to its list without a line here).
    let bare = cbr_render::registry::TECHNIQUES
        .iter()
        .map(|t| t.name)
        .filter(|n| cbr_render::Spec::parse(n).is_ok());
    for text in specs.into_iter().chain(bare) {
        let settings = cbr_render::RenderSettings::parse(64, 36, text).expect("spec");
        let mut listed: Vec<(String, Vec<(String, String)>)> =
            cbr_render::registry::passes(&settings.spec, &ctx)
                .unwrap_or_else(|e| panic!("{text}: {e}"))
                .shaders()
                .into_iter()
                .map(|(shader, mut defines)| {
                    defines.sort();
                    (shader.to_string(), defines)
                })
                .collect();
        listed.sort();
        listed.dedup();
        let mark = shaders.request_mark();
        drop(
            cbr_render::Renderer::new(&gpu, &shaders, &scene, settings)
                .unwrap_or_else(|e| panic!("{text}: {e}")),
        );
        let built: Vec<_> = shaders.requests_since(mark);
        assert!(
            built.iter().any(|(path, _)| path.ends_with(".frag")),
            "`{text}`: no raster pipeline built"
        );
        assert_eq!(
            listed, built,
            "`{text}`: the compile-only list and the build differ"
        );
    }
    common::assert_clean(&gpu);
}

/// A buffer resource grows to a new size under its name, with its declared usage (analytic's
/// tail records and albedo jobs); only a buffer grows.
#[test]
fn a_buffer_resource_grows_under_its_name() {
    let gpu = common::gpu();
    let decls = [
        ResourceDecl::buffer("list", 64).indirect(),
        ResourceDecl::image("img", vk::Format::R32_SFLOAT, 4, 4),
    ];
    let mut res = Resources::new(&gpu, "t", &decls).expect("resources");
    assert_eq!(res.buffer("list").expect("list").size(), 64);
    res.grow(&gpu, "list", 4096).expect("grow");
    assert_eq!(res.buffer("list").expect("list").size(), 4096);
    let live: Vec<(String, u64)> = gpu.allocations();
    assert!(
        live.iter()
            .any(|(name, bytes)| name == "t.list" && *bytes >= 4096),
        "{live:?}"
    );
    assert!(matches!(
        res.grow(&gpu, "img", 4096),
        Err(GpuError::Declaration { .. })
    ));
    assert!(matches!(
        res.grow(&gpu, "nothing", 4096),
        Err(GpuError::Declaration { .. })
    ));
    drop(res);
    common::assert_clean(&gpu);
}
