//! `cbr bench`: arguments and the closing line; the work is in the cbr-bench crate.

use std::path::PathBuf;

use anyhow::{Result, anyhow, bail};
use cbr_bench::{BenchOptions, Shard, SweepFile, help, parse_resolution};
use cbr_render::Spec;
use cbr_scene::desc::{line_of, parse_toml};
use toml::Spanned;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene: a .toml description, an .obj file, or builtin:NAME (`cbr info` lists them);
    /// without one, the sweep file's `scenes`.
    #[arg(required_unless_present_any = ["sweep", "merge"])]
    scene: Option<String>,
    #[arg(long, value_delimiter = ',', default_value = "native", help = help::techniques())]
    techniques: Vec<String>,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Frames rendered before measuring.
    #[arg(long)]
    warmup: Option<u32>,
    /// Measured frames (the protocol asks for at least 50; fewer is allowed for quick looks).
    #[arg(long)]
    frames: Option<u32>,
    /// Sweep: resolutions WxH (replace --width/--height).
    #[arg(long, value_delimiter = ',')]
    resolutions: Vec<String>,
    #[arg(long, value_delimiter = ',', help = help::MAPPINGS)]
    mappings: Vec<String>,
    #[arg(long, value_delimiter = ',', help = help::GROUPS)]
    groups: Vec<u32>,
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_parser = crate::finite_f32, help = help::LOD_BIASES)]
    lod_biases: Vec<f32>,
    /// A TOML file with any of: techniques, resolutions, mappings, groups, lod_biases, warmup,
    /// frames (command-line values win).
    #[arg(long)]
    sweep: Option<PathBuf>,
    /// Crop windows for the report, x,y,w,h (repeatable, at most 4); default: the three windows
    /// with the highest FLIP.
    #[arg(long = "crop", value_name = "X,Y,W,H")]
    crops: Vec<String>,
    #[arg(long, default_value = "native", help = help::REFERENCE)]
    reference: String,
    /// Render cacheable references afresh instead of reading the frame cache.
    #[arg(long)]
    no_cache: bool,
    #[arg(long, help = help::TIME_CACHED_ROWS)]
    time_cached_rows: bool,
    /// Time the passes only: no error, no frames kept, no images (GPU studies at 4K, where the
    /// per-frame metrics would take most of the run). Takes no --reference; native is a row.
    #[arg(long)]
    timing_only: bool,
    /// k of the disocclusion FLIP: the error over pixels whose reference object ID differs from
    /// their ID in any of the k frames before [default: 4].
    #[arg(long, value_name = "K")]
    disocclusion_frames: Option<u32>,
    /// Anisotropic texture filtering: at most N trilinear lookups along a texture footprint's
    /// longer side, in every row and the reference (1 = isotropic; default: each scene's
    /// `anisotropy`, else 1).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(cbr_scene::MAX_ANISOTROPY)))]
    anisotropy: Option<u32>,
    /// Device index or name substring.
    #[arg(long)]
    device: Option<String>,
    /// Validation layers on (slower; messages counted in bench.json).
    #[arg(long)]
    validation: bool,
    /// Render only shard K of the run split N ways (K from 0 to N-1): reference frames, then
    /// configurations x resolutions x scenes, balanced by estimated cost; bench.json holds the
    /// whole plan. Merge the N folders with --merge (docs/cluster.md).
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// The frame cache's folder, shared by the shards of a run [default: $CBR_CACHE_DIR, else
    /// $XDG_CACHE_HOME/cbr, else ~/.cache/cbr].
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Merge these shard folders into -o (bench.json, bench.csv, the images) instead of running.
    #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with_all = ["scene", "sweep", "shard"])]
    merge: Vec<PathBuf>,
    #[arg(short, long, default_value = "out/bench")]
    out: PathBuf,
}

/// The sweep file.
impl BenchArgs {
    fn options(&self) -> Result<BenchOptions> {
        Ok(BenchOptions {
            scene: self.scene.clone().unwrap_or_default(),
            techniques: self.techniques.clone(),
            width: self.width,
            height: self.height,
            warmup: self.warmup,
            frames: self.frames,
            resolutions: self.resolutions.clone(),
            mappings: self.mappings.clone(),
            groups: self.groups.clone(),
            lod_biases: self.lod_biases.clone(),
            sweep: self.sweep.clone(),
            crops: self.crops.clone(),
            reference: self.reference.clone(),
            no_cache: self.no_cache,
            time_cached_rows: self.time_cached_rows,
            timing_only: self.timing_only,
            disocclusion_frames: self.disocclusion_frames,
            anisotropy: self.anisotropy,
            device: self.device.clone(),
            validation: self.validation,
            shard: self.shard.as_deref().map(Shard::parse).transpose()?,
            cache_dir: self.cache_dir.clone(),
            out: self.out.clone(),
        })
    }
}

/// The values of a sweep file that cbr-bench checks without naming the file, read with their
/// lines (unknown keys and wrong types are found by reading it as a `cbr_bench::SweepFile`).
#[derive(serde::Deserialize)]
struct SweepValues {
    scenes: Option<Vec<Spanned<String>>>,
    techniques: Option<Vec<Spanned<String>>>,
    resolutions: Option<Vec<Spanned<String>>>,
    mappings: Option<Vec<Spanned<String>>>,
    groups: Option<Vec<Spanned<u32>>>,
    frames: Option<Spanned<u32>>,
    reference: Option<Spanned<String>>,
}

/// Every bench option and sweep-file value cbr-bench would refuse, refused first with the option
/// or the file, line and key: one clear error before the scene is loaded or a device opened.
fn check(a: &BenchArgs) -> Result<()> {
    for t in &a.techniques {
        Spec::parse(t).map_err(|e| anyhow!("--techniques `{t}`: {e}"))?;
    }
    Spec::parse(&a.reference).map_err(|e| anyhow!("--reference `{}`: {e}", a.reference))?;
    for r in &a.resolutions {
        parse_resolution(r).map_err(|e| anyhow!("--resolutions: {e:#}"))?;
    }
    if let Some(m) = a
        .mappings
        .iter()
        .find(|m| !["pixel", "quad"].contains(&m.as_str()))
    {
        bail!("--mappings `{m}`: the resolve mappings are pixel and quad");
    }
    if let Some(g) = a.groups.iter().find(|g| **g != 8 && **g != 16) {
        bail!("--groups {g}: the resolve groups are 8 and 16");
    }
    if a.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    if let Some(s) = &a.shard {
        Shard::parse(s)?;
    }
    check_crops(a)?;
    match &a.sweep {
        Some(path) => check_sweep(path),
        None => Ok(()),
    }
}

/// A sweep file's values, each refused with the file, line and key.
pub fn check_sweep(path: &std::path::Path) -> Result<()> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow!("{}: cannot read the sweep file: {e}", path.display()))?;
    parse_toml::<SweepFile>(&text, path)?;
    let v: SweepValues = parse_toml(&text, path)?;
    let at = |span: std::ops::Range<usize>, key: &str, msg: String| {
        anyhow!(
            "{}:{}: `{key}`: {msg}",
            path.display(),
            line_of(&text, span.start)
        )
    };
    for (i, sc) in v.scenes.iter().flatten().enumerate() {
        let name = sc.get_ref();
        let file = path.parent().unwrap_or(std::path::Path::new("")).join(name);
        if !name.starts_with("builtin:") && !file.is_file() {
            let msg = format!("no scene file {}", file.display());
            return Err(at(sc.span(), &format!("scenes[{i}]"), msg));
        }
    }
    for (i, t) in v.techniques.iter().flatten().enumerate() {
        Spec::parse(t.get_ref()).map_err(|e| at(t.span(), &format!("techniques[{i}]"), e))?;
    }
    if let Some(r) = &v.reference {
        Spec::parse(r.get_ref()).map_err(|e| at(r.span(), "reference", e))?;
    }
    for (i, r) in v.resolutions.iter().flatten().enumerate() {
        parse_resolution(r.get_ref())
            .map_err(|e| at(r.span(), &format!("resolutions[{i}]"), format!("{e:#}")))?;
    }
    for (i, m) in v.mappings.iter().flatten().enumerate() {
        if !["pixel", "quad"].contains(&m.get_ref().as_str()) {
            let msg = format!("`{}`: the resolve mappings are pixel and quad", m.get_ref());
            return Err(at(m.span(), &format!("mappings[{i}]"), msg));
        }
    }
    for (i, g) in v.groups.iter().flatten().enumerate() {
        if *g.get_ref() != 8 && *g.get_ref() != 16 {
            let msg = format!("{}: the resolve groups are 8 and 16", g.get_ref());
            return Err(at(g.span(), &format!("groups[{i}]"), msg));
        }
    }
    if let Some(f) = &v.frames
        && *f.get_ref() == 0
    {
        return Err(at(f.span(), "frames", "must be at least 1".into()));
    }
    Ok(())
}

/// `--crop` windows that cannot fit the resolutions the options name (cbr-bench finds out only
/// after measuring): refused first. Resolutions that come from the scene or the sweep file are
/// left to cbr-bench.
fn check_crops(a: &BenchArgs) -> Result<()> {
    let resolutions: Vec<(u32, u32)> = match (a.width, a.height) {
        _ if !a.resolutions.is_empty() => a
            .resolutions
            .iter()
            .map(|r| parse_resolution(r))
            .collect::<Result<_>>()?,
        (Some(w), Some(h)) => vec![(w, h)],
        _ => return Ok(()),
    };
    for c in &a.crops {
        let v: Vec<u64> = c
            .split(',')
            .map(|x| x.trim().parse::<u64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| anyhow!("--crop {c}: expected X,Y,W,H: {e}"))?;
        let [x, y, w, h] = v[..] else {
            bail!("--crop {c}: expected X,Y,W,H");
        };
        if let Some((rw, rh)) = resolutions
            .iter()
            .find(|(rw, rh)| x + w > u64::from(*rw) || y + h > u64::from(*rh))
        {
            bail!("--crop {c} does not fit in {rw}x{rh}");
        }
    }
    Ok(())
}

pub fn run(a: &BenchArgs) -> Result<()> {
    if !a.merge.is_empty() {
        let m = cbr_bench::merge::merge(&a.merge)?;
        cbr_bench::merge::write(&m, &a.out)?;
        println!(
            "{} shard folder(s), {} row(s): {}",
            a.merge.len(),
            m.json["rows"].as_array().map_or(0, Vec::len),
            a.out.join("bench.json").display()
        );
        return Ok(());
    }
    check(a)?;
    let options = a.options()?;
    // A failed bench leaves no output folder it made (snapshots of a run without bench.json).
    let made = !a.out.exists();
    let r = cbr_bench::run(&options).inspect_err(|_| {
        if made && a.out.is_dir() {
            let _ = std::fs::remove_dir_all(&a.out);
        }
    })?;
    println!(
        "{} configuration(s) x {} resolution(s) of {}: {}",
        r.configurations,
        r.resolutions,
        r.scene,
        r.bench_json.display()
    );
    Ok(())
}
