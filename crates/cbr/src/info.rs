//! `cbr info`: devices, driver, the limits that matter here, and the runnable layouts.

use anyhow::Result;
use cbr_gpu::{Gpu, GpuOptions};

#[derive(clap::Args)]
pub struct InfoArgs {
    /// Device index or name substring.
    #[arg(long)]
    device: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(a: &InfoArgs) -> Result<()> {
    let report = Gpu::enumerate()?;
    let gpu = Gpu::new(&GpuOptions {
        device: a.device.clone(),
        validation: false,
    })?;
    let caps = gpu.caps();
    let layouts = cbr_bench::render::device::layouts_json(caps);
    if a.json {
        let devices: Vec<serde_json::Value> = report
            .candidates
            .iter()
            .map(|c| serde_json::json!({"index": c.index, "name": c.name, "kind": c.kind, "rejected": c.rejection()}))
            .collect();
        let scenes: Vec<serde_json::Value> = std::iter::once(
            serde_json::json!({"name": "demo", "about": "every hard case in one scene"}),
        )
        .chain(
            cbr_scene::cases::CASES
                .iter()
                .map(|c| serde_json::json!({"name": c.name, "about": c.about})),
        )
        .collect();
        let v = serde_json::json!({"devices": devices, "chosen": gpu.info(), "caps": caps, "layouts": layouts, "scenes": scenes});
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("Vulkan devices:");
    for c in &report.candidates {
        let mark = if c.index == gpu.info().index {
            "*"
        } else {
            " "
        };
        let why = c
            .rejection()
            .map(|r| format!("  (unusable: {r})"))
            .unwrap_or_default();
        println!(
            " {mark}[{}] {} ({:?}, Vulkan {}.{}){why}",
            c.index, c.name, c.kind, c.api.0, c.api.1
        );
    }
    let i = gpu.info();
    println!(
        "\nchosen: [{}] {}\n  driver: {} {}\n  API: {}",
        i.index, i.name, i.driver_name, i.driver_info, i.api_version
    );
    if !caps.can_execute {
        println!(
            "  cannot execute: it can only compile pipelines (RADV's null device: no memory); \
             render and bench are refused here"
        );
    }
    println!(
        "  subgroup size {}, compute can require {:?}, pipeline executable statistics {}",
        caps.subgroup_size, caps.compute_subgroup_sizes, caps.pipeline_executable_info
    );
    println!(
        "  sample counts (colour+depth): {:?}; integer colour: {:?}",
        caps.sample_counts, caps.integer_color_sample_counts
    );
    println!(
        "  sampleRateShading {}, sample locations {}, maintenance4 {}, dynamic rendering {}, geometry shader {}, gl_Layer from VS {}, multiview {} (cbr does not use it)",
        caps.sample_rate_shading,
        caps.sample_locations,
        caps.maintenance4,
        caps.dynamic_rendering,
        caps.geometry_shader,
        caps.shader_output_layer,
        caps.multiview
    );
    println!(
        "  timestamps {} ({} valid bits, {} ns/tick), pipeline statistics {}",
        caps.timestamps,
        caps.timestamp_valid_bits,
        caps.timestamp_period_ns,
        caps.pipeline_statistics
    );
    println!(
        "  max image {}, max framebuffer {}x{}, sub-pixel bits {} (viewport {}), sub-texel bits {}",
        caps.max_image_dimension_2d,
        caps.max_framebuffer[0],
        caps.max_framebuffer[1],
        caps.sub_pixel_precision_bits,
        caps.viewport_sub_pixel_bits,
        caps.sub_texel_precision_bits
    );
    let bytes = cbr_render::memory::human_bytes;
    println!(
        "  memory: largest device-local heap {}{}, maxMemoryAllocationSize {}, \
         maxStorageBufferRange {} (renders that cannot fit are refused before allocating)",
        bytes(caps.device_local_heap_bytes),
        if caps.unified_memory {
            " (unified: host-visible memory shares it)"
        } else {
            ""
        },
        bytes(caps.max_memory_allocation_size),
        bytes(u64::from(caps.max_storage_buffer_range))
    );
    println!("\ntechniques (--technique SPEC, bench --techniques; post passes append +PASS):");
    for t in cbr_render::registry::TECHNIQUES {
        let params: Vec<&str> = Vec::new();
        let runs = match (t.needs)(&params, caps) {
            None => String::new(),
            Some(why) => format!(" (here: needs {why})"),
        };
        println!("  {:44} {}{runs}", t.grammar, t.about);
    }
    for p in cbr_render::registry::POST_PASSES {
        println!("  +{:43} {}", p.grammar, p.about);
    }
    for line in cbr_bench::render::device::layouts_text(caps) {
        println!("{line}");
    }
    println!("\nbuilt-in scenes (builtin:NAME; docs/hard-cases.md runs every technique on each):");
    println!(
        "  {:12} the demo: every hard case below in one scene",
        "demo"
    );
    for c in cbr_scene::cases::CASES {
        println!("  {:12} {}", c.name, c.about);
    }
    Ok(())
}
