//! `cbr gpu-stats`: every pipeline the specs use, compiled by AMD's real compiler (ACO) for each
//! GPU family on RADV's null device, with the driver's statistics, and a static cost model per
//! pass ([`model`]). docs/gpu-isa.md has the method, the limits and the figures.
//!
//! Three steps:
//! 1. **Trace** (the executing device, lavapipe here): one frame of each spec is rendered and
//!    what each pass declared it reads, writes and dispatches (cbr_gpu::Traffic) is kept with
//!    its raster pipeline statistics (vertex and fragment invocations). The frame is the second
//!    (frame 1), so temporal passes run with a history. `--model-only` traces the frame with the
//!    scene's objects removed: its compute passes run at their full size, its raster passes draw
//!    nothing, and rows whose cost needs the raster say so instead of a model.
//! 2. **Compile** (one child process per family, all at once: RADV reads `RADV_FORCE_FAMILY`
//!    once per process): the passes of each spec, through the declarations rendering uses
//!    (`registry::passes`, `ComputeDecl::build`, `GraphicsDecl::build`), with the validation
//!    layers on; where a family runs compute both as wave64 and wave32 (RDNA), its compute passes
//!    are compiled as both.
//! 3. **Join**: each compiled pipeline is matched to the traced pass that ran it and modelled.
//!    Output: `gpu-stats.json` (byte-identical on reruns: it holds no timing), `gpu-stats.csv`,
//!    `lavapipe-timings.json` (the traced frame's pass times, which do vary), the disassembly
//!    per pass when asked, and a table on stdout.

pub mod model;
mod output;

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use cbr_gpu::{CompileSettings, Gpu, GpuOptions, PassTiming, null_device};
use cbr_render::{RenderSettings, Renderer, Spec};
use serde::{Deserialize, Serialize};

pub use output::{table, write_outputs};

/// The families `--families` defaults to: GCN 4, GCN 5 (the Stadia write-up's Vega), RDNA 2,
/// RDNA 3.
pub const DEFAULT_FAMILIES: &[&str] = &["polaris10", "vega10", "navi21", "gfx1100"];

#[derive(Clone, Debug)]
pub struct GpuStatsOptions {
    /// A scene (TOML, OBJ or builtin:NAME).
    pub scene: String,
    /// Technique specs; empty: every registered technique by its bare name.
    pub specs: Vec<String>,
    pub families: Vec<String>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub disassembly: bool,
    pub model_only: bool,
    pub out: PathBuf,
    /// The device the frame is traced on (default: the usual pick).
    pub device: Option<String>,
    /// The program a family's child process runs (`cbr`): `EXE gpu-stats --child FAMILY ...`.
    pub exe: PathBuf,
}

/// One executable of one compiled pipeline on one family (a child's answer).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Compiled {
    pub spec: String,
    /// The pipeline's declared name.
    pub pass: String,
    /// `compute` or `graphics`.
    pub kind: String,
    /// The stages the executable runs (`compute`, `vertex`, `fragment`, `vertex+geometry`, ...).
    pub stage: String,
    /// The wave size it runs with (64 or 32).
    pub wave: u32,
    /// Every statistic, by the driver's own name.
    pub stats: serde_json::Map<String, serde_json::Value>,
    /// The GCN/RDNA disassembly, when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disassembly: Option<String>,
}

/// What a family's child process writes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChildOutput {
    pub family: String,
    pub device: String,
    pub driver: String,
    pub compiled: Vec<Compiled>,
    /// (spec, why) of the specs the family's device cannot run.
    pub refused: Vec<(String, String)>,
    pub validation_messages: Vec<String>,
    /// Pipelines the driver crashed on (filled by the parent).
    #[serde(default)]
    pub crashed: Vec<Crash>,
}

/// What one spec's traced frame did, pass by pass (passes of one name summed).
#[derive(Clone, Debug)]
pub struct Traced {
    pub spec: String,
    pub passes: Vec<PassTiming>,
    /// Why the tracing device could not run it (its pipelines are still compiled and listed,
    /// without a model): lavapipe has no 2x MSAA, for one.
    pub error: Option<String>,
}

/// The specs to study: the given ones (each checked against the registries), or every
/// registered technique: by its bare name, or where that needs a parameter (`ssaa:N`,
/// `interleaved:MxN`), with the first of `:4`, `:4x4`, `:2`, `:2x2` its grammar accepts.
pub fn specs(given: &[String]) -> Result<Vec<String>> {
    if given.is_empty() {
        return Ok(cbr_render::registry::TECHNIQUES
            .iter()
            .filter_map(|t| {
                ["", ":4", ":4x4", ":2", ":2x2"]
                    .iter()
                    .map(|p| format!("{}{p}", t.name))
                    .find(|s| Spec::parse(s).is_ok())
            })
            .collect());
    }
    for s in given {
        Spec::parse(s).map_err(anyhow::Error::msg)?;
    }
    Ok(given.to_vec())
}

/// Runs the whole study and writes its outputs; returns the stdout table.
pub fn run(a: &GpuStatsOptions) -> Result<String> {
    let specs = specs(&a.specs)?;
    if a.families.is_empty() {
        bail!(
            "--families names no family (e.g. {})",
            DEFAULT_FAMILIES.join(",")
        );
    }
    let mut families: Vec<String> = Vec::new();
    for f in &a.families {
        null_device::env(f).with_context(|| format!("--families {f}"))?;
        let f = f.trim().to_lowercase();
        if !families.contains(&f) {
            families.push(f);
        }
    }
    let mut scene = cbr_scene::load(&a.scene, &Default::default())?;
    let s = &mut scene.settings;
    s.width = a.width.unwrap_or(s.width);
    s.height = a.height.unwrap_or(s.height);
    cbr_scene::check_resolution(s.width, s.height).map_err(anyhow::Error::msg)?;
    let size = (s.width, s.height);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create the output folder {}", a.out.display()))?;

    // The families compile in their own processes while this one traces.
    let children = families
        .iter()
        .map(|f| spawn_child(a, f, &specs, size, &materials, &[]))
        .collect::<Result<Vec<_>>>()?;
    let started = std::time::Instant::now();
    let traced = trace(a, &mut scene, &specs)?;
    tracing::info!(
        "traced {} spec(s) in {:.1} s",
        specs.len(),
        started.elapsed().as_secs_f64()
    );
    let mut outputs = Vec::new();
    for (family, child, file) in children {
        outputs.push(answer(a, &family, child, &file, &specs, size, &materials)?);
        tracing::info!(
            "{family} compiled after {:.1} s",
            started.elapsed().as_secs_f64()
        );
    }
    let study = output::Study::join(&scene.source, size, a.model_only, &outputs, &traced);
    write_outputs(&a.out, &study, &outputs, &traced, a.disassembly)?;
    let messages: usize = outputs.iter().map(|o| o.validation_messages.len()).sum();
    if messages > 0 {
        let first: Vec<&str> = outputs
            .iter()
            .flat_map(|o| o.validation_messages.iter().map(String::as_str))
            .take(3)
            .collect();
        bail!(
            "{messages} validation message(s) while compiling (outputs written to {}): {}",
            a.out.display(),
            first.join("\n")
        );
    }
    Ok(table(&study))
}

/// How many pipelines that crash the driver a family may skip before the study gives up.
const MAX_CRASHES: usize = 8;

/// Waits for `family`'s compiler process and reads its answer. Where the driver crashes
/// compiling a pipeline (RADV 22.3 does, on a few), the process is run again without that
/// pipeline, which the answer then lists in `crashed` (the child says on stderr which pipeline
/// it is compiling).
fn answer(
    a: &GpuStatsOptions,
    family: &str,
    mut child: std::process::Child,
    file: &Path,
    specs: &[String],
    size: (u32, u32),
    materials: &[u32],
) -> Result<ChildOutput> {
    let mut crashed: Vec<Crash> = Vec::new();
    loop {
        let out = child
            .wait_with_output()
            .with_context(|| format!("waiting for {family}'s compiler process"))?;
        let text = std::fs::read_to_string(file);
        let _ = std::fs::remove_file(file);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if out.status.success() {
            let text = text.with_context(|| format!("{family}'s compiler wrote no answer"))?;
            let mut answer: ChildOutput = serde_json::from_str(&text)
                .with_context(|| format!("{family}'s compiler answer"))?;
            answer.crashed = crashed;
            return Ok(answer);
        }
        // Killed by a signal (no exit code) while compiling a named pipeline: skip it, again.
        let last = stderr
            .lines()
            .rev()
            .find_map(|l| l.strip_prefix(COMPILING))
            .and_then(|l| serde_json::from_str::<Crash>(l).ok());
        match last {
            Some(c) if out.status.code().is_none() && crashed.len() < MAX_CRASHES => {
                tracing::warn!(
                    "the {family} driver crashed ({}) compiling `{}` of `{}`; compiling the rest without it",
                    out.status,
                    c.pass,
                    c.spec
                );
                crashed.push(Crash {
                    signal: out.status.to_string(),
                    ..c
                });
                let skip: Vec<String> = crashed
                    .iter()
                    .map(|c| format!("{}|{}", c.spec, c.pass))
                    .collect();
                child = spawn_child(a, family, specs, size, materials, &skip)?.1;
            }
            _ => bail!(
                "compiling for {family} failed ({}): {}",
                out.status,
                stderr
                    .lines()
                    .filter(|l| !l.starts_with(COMPILING))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .trim()
            ),
        }
    }
}

/// What a child writes on stderr before each pipeline it compiles (then a [`Crash`] as JSON).
const COMPILING: &str = "compiling: ";

/// A pipeline the driver crashed on: the study lists it and goes on without it.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Crash {
    pub spec: String,
    pub pass: String,
    /// The required compute wave size (`None`: the driver's choice).
    pub wave: Option<u32>,
    #[serde(default)]
    pub signal: String,
}

/// Starts `family`'s compiler process (without the pipelines `skip` names, as `SPEC|PASS`);
/// returns it with the file it answers in.
fn spawn_child(
    a: &GpuStatsOptions,
    family: &str,
    specs: &[String],
    size: (u32, u32),
    materials: &[u32],
    skip: &[String],
) -> Result<(String, std::process::Child, PathBuf)> {
    let family = family.trim().to_lowercase();
    let file = a.out.join(format!(".{family}.compiled.json"));
    let mut c = Command::new(&a.exe);
    c.arg("gpu-stats")
        .args(["--child", &family])
        .args(["--techniques", &specs.join(",")])
        .args([
            "--width",
            &size.0.to_string(),
            "--height",
            &size.1.to_string(),
        ])
        .args([
            "--materials",
            &materials
                .iter()
                .map(u32::to_string)
                .collect::<Vec<_>>()
                .join(","),
        ])
        .arg("-o")
        .arg(&file);
    if a.disassembly {
        c.arg("--disassembly");
    }
    if !skip.is_empty() {
        c.args(["--skip", &skip.join(",")]);
    }
    null_device::set_env(&mut c, &family)?;
    c.env("CBR_ANY_DEVICE", "1");
    c.stdout(std::process::Stdio::null());
    c.stderr(std::process::Stdio::piped());
    let child = c
        .spawn()
        .with_context(|| format!("cannot run {} for {family}", a.exe.display()))?;
    Ok((family, child, file))
}

/// Renders frames 0 and 1 of each spec on the executing device; frame 1's passes.
fn trace(
    a: &GpuStatsOptions,
    scene: &mut cbr_scene::Scene,
    specs: &[String],
) -> Result<Vec<Traced>> {
    if a.model_only {
        // No scene raster: the passes run at their size over an empty frame.
        scene.objects.clear();
    }
    let gpu = Gpu::new(&GpuOptions {
        device: a.device.clone(),
        validation: false,
    })?;
    gpu.require_execution("tracing a frame")?;
    let shaders = cbr_render::shader_library();
    let (w, h) = (scene.settings.width, scene.settings.height);
    let mut out = Vec::new();
    for text in specs {
        let spec = Spec::parse(text).map_err(anyhow::Error::msg)?;
        let settings = RenderSettings::new(w, h, spec);
        // A spec the tracing device cannot run (an unsupported layout, memory) is said in its
        // rows; anything else is an error.
        let traced = Renderer::check(&gpu, scene, &settings)
            .map_err(|e| e.to_string())
            .and_then(|_| {
                let mut r =
                    Renderer::new(&gpu, &shaders, scene, settings).map_err(|e| e.to_string())?;
                r.render(scene, 0).map_err(|e| e.to_string())?;
                r.render(scene, 1).map_err(|e| e.to_string())
            });
        out.push(match traced {
            Ok(f) => Traced {
                spec: text.clone(),
                passes: f.timings,
                error: None,
            },
            Err(e) => {
                tracing::warn!("`{text}` cannot be traced on {}: {e}", gpu.info().name);
                Traced {
                    spec: text.clone(),
                    passes: Vec::new(),
                    error: Some(format!(
                        "the tracing device {} cannot run it: {e}",
                        gpu.info().name
                    )),
                }
            }
        });
    }
    Ok(out)
}

/// A family's child process: compiles every pass of `specs` on this process's device (the
/// family's null device) with statistics on, and writes [`ChildOutput`] to `file`.
/// What a family's child process is asked (`cbr gpu-stats --child FAMILY ...`).
#[derive(Clone, Debug)]
pub struct ChildArgs {
    pub family: String,
    pub specs: Vec<String>,
    pub size: (u32, u32),
    pub materials: Vec<u32>,
    pub disassembly: bool,
    /// Also compile compute as wave32 where the family runs it.
    pub wave32: bool,
    /// `SPEC|PASS` of pipelines not to compile (the driver crashed on them).
    pub skip: Vec<String>,
    /// The answer file.
    pub file: PathBuf,
}

pub fn child(a: &ChildArgs) -> Result<()> {
    let ChildArgs {
        family,
        specs,
        size,
        materials,
        disassembly,
        wave32,
        skip,
        file,
    } = a;
    let (size, disassembly, wave32) = (*size, *disassembly, *wave32);
    let gpu = Gpu::new(&GpuOptions {
        device: None,
        validation: true,
    })?;
    let name = gpu.info().name.clone();
    if !name.to_lowercase().contains(&format!("radv {family}")) {
        bail!("the device is {name}, not RADV's null device for {family}");
    }
    let shaders = cbr_render::shader_library();
    let ctx = cbr_render::technique::PassCtx {
        caps: gpu.caps(),
        width: size.0,
        height: size.1,
        instrument: false,
        geometry: false,
        materials,
    };
    // Compute as the driver chooses (wave64 on every family RADV 22.3 knows), then as wave32
    // where the family also runs that. Not by requiring 64 in the first round: RADV 22.3 on
    // navi21 crashes compiling `analytic.resolve` with a required subgroup size of 64.
    let waves: Vec<Option<u32>> = if wave32 && gpu.caps().compute_subgroup_sizes.contains(&32) {
        vec![None, Some(32)]
    } else {
        vec![None]
    };
    let mut compiled = Vec::new();
    let mut refused = Vec::new();
    for text in specs {
        let spec = Spec::parse(text).map_err(anyhow::Error::msg)?;
        let t = cbr_render::registry::find(&spec.technique.name)
            .with_context(|| format!("no technique `{}`", spec.technique.name))?;
        if let Some(why) = (t.needs)(&spec.technique.params(), gpu.caps()) {
            refused.push((text.clone(), why));
            continue;
        }
        let list = cbr_render::registry::passes(&spec, &ctx).map_err(anyhow::Error::msg)?;
        for (round, wave) in waves.iter().enumerate() {
            gpu.set_compile_settings(CompileSettings {
                statistics: true,
                representations: disassembly,
                compute_subgroup_size: *wave,
            })?;
            let say = |pass: &str| {
                let c = Crash {
                    spec: text.clone(),
                    pass: pass.to_string(),
                    wave: *wave,
                    signal: String::new(),
                };
                eprintln!(
                    "{COMPILING}{}",
                    serde_json::to_string(&c).unwrap_or_default()
                );
            };
            let skipped = |pass: &str| skip.iter().any(|s| *s == format!("{text}|{pass}"));
            for d in list.compute.iter().filter(|d| !skipped(&d.name)) {
                say(&d.name);
                d.build(&gpu, &shaders)
                    .with_context(|| format!("{family}: `{text}`: {}", d.name))?;
            }
            // Raster pipelines once (no wave choice for them).
            if round == 0 {
                for d in list.graphics.iter().filter(|d| !skipped(&d.name)) {
                    say(&d.name);
                    d.build(&gpu, &shaders)
                        .with_context(|| format!("{family}: `{text}`: {}", d.name))?;
                }
            }
            for p in gpu.take_captured() {
                for e in &p.executables {
                    compiled.push(Compiled {
                        spec: text.clone(),
                        pass: p.pipeline.clone(),
                        kind: p.kind.to_string(),
                        stage: e.stage.clone(),
                        wave: e.subgroup_size,
                        stats: e
                            .stats
                            .iter()
                            .map(|(k, v)| {
                                (
                                    k.clone(),
                                    serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
                                )
                            })
                            .collect(),
                        disassembly: e.representation("Assembly").map(str::to_string),
                    });
                }
            }
        }
    }
    let out = ChildOutput {
        family: family.to_string(),
        device: name,
        driver: format!("{} {}", gpu.info().driver_name, gpu.info().driver_info),
        compiled,
        refused,
        validation_messages: gpu.validation().messages(),
        crashed: Vec::new(),
    };
    let text = serde_json::to_string(&out)?;
    std::fs::write(file, text).with_context(|| format!("cannot write {}", file.display()))?;
    Ok(())
}

/// The traced pass a pipeline ran in: its name with `.mat<N>` (material variant) segments
/// dropped, exactly, else the longest traced name it extends at a `.` or `_`
/// (`analytic.albedo_plan` runs in `analytic.albedo`).
pub fn scope_of<'a>(pipeline: &str, passes: &'a [PassTiming]) -> Option<&'a PassTiming> {
    let plain: Vec<&str> = pipeline
        .split('.')
        .filter(|seg| {
            !(seg.len() > 3
                && seg.starts_with("mat")
                && seg[3..].bytes().all(|b| b.is_ascii_digit()))
        })
        .collect();
    let plain = plain.join(".");
    let usable = |p: &&PassTiming| p.name != "readback" && !p.name.starts_with("readback.");
    if let Some(p) = passes.iter().filter(usable).find(|p| p.name == plain) {
        return Some(p);
    }
    passes
        .iter()
        .filter(usable)
        .filter(|p| {
            plain
                .strip_prefix(p.name.as_str())
                .is_some_and(|rest| rest.starts_with(['.', '_']))
        })
        .max_by_key(|p| p.name.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(name: &str) -> PassTiming {
        PassTiming {
            name: name.into(),
            gpu_ms: 0.0,
            stats: None,
            traffic: Default::default(),
        }
    }

    #[test]
    fn pipelines_find_the_pass_they_ran_in() {
        let traced: Vec<PassTiming> = [
            "native.raster.depth",
            "native.raster",
            "resolve",
            "analytic.albedo",
            "readback",
        ]
        .map(pass)
        .into();
        let of = |p: &str| scope_of(p, &traced).map(|t| t.name.clone());
        // Material variants run in their pass; the depth pre-pass's variants in its own.
        assert_eq!(of("native.raster.mat3").as_deref(), Some("native.raster"));
        assert_eq!(
            of("native.raster.mat3.depth").as_deref(),
            Some("native.raster.depth")
        );
        assert_eq!(
            of("native.raster.mat0.late").as_deref(),
            Some("native.raster")
        );
        assert_eq!(of("resolve").as_deref(), Some("resolve"));
        assert_eq!(
            of("analytic.albedo.order").as_deref(),
            Some("analytic.albedo")
        );
        // Dispatches of one scope named after it (`analytic.albedo_plan` in `analytic.albedo`).
        assert_eq!(
            of("analytic.albedo_plan").as_deref(),
            Some("analytic.albedo")
        );
        // A name that merely starts like a pass is not in it; readbacks are nobody's scope.
        assert_eq!(of("resolved"), None);
        assert_eq!(of("readback.post"), None);
        assert_eq!(of("taa"), None);
        // "material" is not a variant segment.
        assert_eq!(of("native.raster.material"), Some("native.raster".into()));
    }
}
