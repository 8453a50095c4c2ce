//! What the driver's compiler made of each pipeline (VK_KHR_pipeline_executable_properties): per
//! executable its stages, subgroup size, every statistic by the driver's own name, and on request
//! its internal representations (RADV: NIR, ACO IR, the GCN/RDNA disassembly). Plus the compute
//! wave size. Both are device-level settings ([`CompileSettings`], `Gpu::set_compile_settings`)
//! that every pipeline creation honours, so the declarations rendering uses compile unchanged.

use std::ffi::{CStr, c_char, c_void};

use ash::vk;
use serde::{Serialize, Serializer};

use crate::context::{Gpu, Inner};
use crate::error::{GpuError, Result, VkContext};

/// What every pipeline creation on a device also asks of the driver. Default: nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CompileSettings {
    /// Create pipelines with VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR and read their
    /// statistics ([`crate::Pipeline::executables`], [`Gpu::take_captured`]).
    pub statistics: bool,
    /// Also capture internal representations (VK_PIPELINE_CREATE_CAPTURE_INTERNAL_
    /// REPRESENTATIONS_BIT_KHR): the disassembly. Implies `statistics`.
    pub representations: bool,
    /// The subgroup (wave) size every compute pipeline requires
    /// (VkPipelineShaderStageRequiredSubgroupSizeCreateInfo); `None`: the driver's choice.
    /// One of `Caps::compute_subgroup_sizes`.
    pub compute_subgroup_size: Option<u32>,
}

impl CompileSettings {
    pub fn captures(&self) -> bool {
        self.statistics || self.representations
    }

    /// The pipeline creation flags these settings add.
    pub(crate) fn flags(&self) -> vk::PipelineCreateFlags {
        let mut f = vk::PipelineCreateFlags::empty();
        if self.captures() {
            f |= vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR;
        }
        if self.representations {
            f |= vk::PipelineCreateFlags::CAPTURE_INTERNAL_REPRESENTATIONS_KHR;
        }
        f
    }

    /// Why `caps` cannot honour these settings, or `None`.
    pub fn unsupported(&self, caps: &crate::Caps) -> Option<String> {
        let mut why = Vec::new();
        if self.captures() && !caps.pipeline_executable_info {
            why.push(
                "pipeline statistics (VK_KHR_pipeline_executable_properties, pipelineExecutableInfo)"
                    .to_string(),
            );
        }
        if let Some(n) = self.compute_subgroup_size
            && !caps.compute_subgroup_sizes.contains(&n)
        {
            why.push(format!(
                "a required compute subgroup size of {n} (it allows {:?})",
                caps.compute_subgroup_sizes
            ));
        }
        (!why.is_empty()).then(|| why.join(", "))
    }
}

/// One statistic's value, as the driver typed it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum StatValue {
    Bool(bool),
    I64(i64),
    U64(u64),
    F64(f64),
}

impl StatValue {
    /// The value as a number (a bool as 0 or 1).
    pub fn as_f64(&self) -> f64 {
        match *self {
            StatValue::Bool(b) => f64::from(u8::from(b)),
            StatValue::I64(v) => v as f64,
            StatValue::U64(v) => v as f64,
            StatValue::F64(v) => v,
        }
    }
}

fn ordered_map<S: Serializer, V: Serialize>(
    v: &[(String, V)],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.collect_map(v.iter().map(|(k, v)| (k, v)))
}

/// One executable of a pipeline: what the driver compiled for one or more stages (RADV on GFX9
/// merges vertex and geometry into one).
#[derive(Clone, Debug, Serialize)]
pub struct ExecutableStats {
    /// The stages it runs, `+`-joined: `compute`, `vertex`, `fragment`, `vertex+geometry`, ...
    pub stage: String,
    pub name: String,
    pub description: String,
    /// The subgroup (wave) size it runs with; 0 where the driver does not say.
    pub subgroup_size: u32,
    /// Every statistic in the driver's order, by the driver's own name (RADV: "SGPRs", "VGPRs",
    /// "Code size", "Instructions", "Latency", "Inverse Throughput", ...). JSON: an object.
    #[serde(serialize_with = "ordered_map")]
    pub stats: Vec<(String, StatValue)>,
    /// (name, text) of each internal representation, when captured (RADV: "NIR Shader(s)",
    /// "ACO IR", "Assembly"). JSON: an object.
    #[serde(serialize_with = "ordered_map")]
    pub representations: Vec<(String, String)>,
}

impl ExecutableStats {
    /// The statistic called `name` (the driver's spelling).
    pub fn stat(&self, name: &str) -> Option<StatValue> {
        self.stats.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// The internal representation called `name`.
    pub fn representation(&self, name: &str) -> Option<&str> {
        self.representations
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| t.as_str())
    }
}

/// What the driver reported for one pipeline created with capture on.
#[derive(Clone, Debug, Serialize)]
pub struct PipelineExecutables {
    /// The pipeline's name (its declaration's, as given to `Pipeline::compute/graphics`).
    pub pipeline: String,
    /// `compute` or `graphics`.
    pub kind: &'static str,
    /// The subgroup size it was compiled to require (compute only), or `None`.
    pub required_subgroup_size: Option<u32>,
    pub executables: Vec<ExecutableStats>,
}

impl PipelineExecutables {
    /// The executables that run `stage` (`"compute"`, `"fragment"`, ...).
    pub fn for_stage<'a>(&'a self, stage: &'a str) -> impl Iterator<Item = &'a ExecutableStats> {
        self.executables
            .iter()
            .filter(move |e| e.stage.split('+').any(|s| s == stage))
    }
}

/// `+`-joined names of the stages in `flags`.
pub(crate) fn stage_names(flags: vk::ShaderStageFlags) -> String {
    const NAMES: [(vk::ShaderStageFlags, &str); 6] = [
        (vk::ShaderStageFlags::VERTEX, "vertex"),
        (vk::ShaderStageFlags::TESSELLATION_CONTROL, "tess_control"),
        (vk::ShaderStageFlags::TESSELLATION_EVALUATION, "tess_eval"),
        (vk::ShaderStageFlags::GEOMETRY, "geometry"),
        (vk::ShaderStageFlags::FRAGMENT, "fragment"),
        (vk::ShaderStageFlags::COMPUTE, "compute"),
    ];
    let known = NAMES
        .iter()
        .fold(vk::ShaderStageFlags::empty(), |a, n| a | n.0);
    let mut names: Vec<String> = NAMES
        .iter()
        .filter(|(f, _)| flags.contains(*f))
        .map(|(_, n)| n.to_string())
        .collect();
    if !(flags & !known).is_empty() {
        names.push(format!("{:#x}", (flags & !known).as_raw()));
    }
    names.join("+")
}

/// A fixed-size C string from the driver, up to its NUL (or the whole array).
fn c_text(chars: &[c_char]) -> String {
    let bytes: Vec<u8> = chars
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Reads every executable of `pipeline`, created with the capture flags of `settings`.
pub(crate) fn read(
    inner: &Inner,
    pipeline: vk::Pipeline,
    name: &str,
    kind: &'static str,
    settings: &CompileSettings,
) -> Result<PipelineExecutables> {
    let loader = inner.executable_properties.as_ref().ok_or_else(|| {
        GpuError::Other("pipeline statistics were captured without the extension".into())
    })?;
    let pinfo = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: `pipeline` is a live pipeline of this device; the wrapper sizes the output.
    let props = unsafe { loader.get_pipeline_executable_properties(&pinfo) }
        .vk("vkGetPipelineExecutablePropertiesKHR")?;
    let mut executables = Vec::with_capacity(props.len());
    for (i, p) in props.iter().enumerate() {
        let info = vk::PipelineExecutableInfoKHR::default()
            .pipeline(pipeline)
            .executable_index(i as u32);
        // SAFETY: as above; `i` is below the executable count just read.
        let raw = unsafe { loader.get_pipeline_executable_statistics(&info) }
            .vk("vkGetPipelineExecutableStatisticsKHR")?;
        let stats = raw
            .iter()
            .map(|s| {
                // SAFETY: `format` says which member of the union the driver wrote.
                let v = unsafe {
                    match s.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                            StatValue::Bool(s.value.b32 != 0)
                        }
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => {
                            StatValue::I64(s.value.i64)
                        }
                        vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => {
                            StatValue::F64(s.value.f64)
                        }
                        _ => StatValue::U64(s.value.u64),
                    }
                };
                (c_text(&s.name), v)
            })
            .collect();
        // Never asked of a pipeline created without the capture flag: that crashes RADV.
        let representations = if settings.representations {
            representations(loader, &info)?
        } else {
            Vec::new()
        };
        executables.push(ExecutableStats {
            stage: stage_names(p.stages),
            name: c_text(&p.name),
            description: c_text(&p.description),
            subgroup_size: p.subgroup_size,
            stats,
            representations,
        });
    }
    Ok(PipelineExecutables {
        pipeline: name.to_string(),
        kind,
        required_subgroup_size: if kind == "compute" {
            settings.compute_subgroup_size
        } else {
            None
        },
        executables,
    })
}

/// The internal representations of one executable: count, then names and sizes, then the data
/// into buffers allocated here.
fn representations(
    loader: &ash::khr::pipeline_executable_properties::Device,
    info: &vk::PipelineExecutableInfoKHR,
) -> Result<Vec<(String, String)>> {
    let fp = loader
        .fp()
        .get_pipeline_executable_internal_representations_khr;
    let device = loader.device();
    let mut count = 0u32;
    // SAFETY: a count query on a pipeline created with the capture-representations flag.
    unsafe { fp(device, info, &mut count, std::ptr::null_mut()) }
        .result()
        .vk("vkGetPipelineExecutableInternalRepresentationsKHR")?;
    let mut reps = vec![vk::PipelineExecutableInternalRepresentationKHR::default(); count as usize];
    // SAFETY: `reps` holds `count` structs with null data pointers: the driver writes names and
    // sizes only.
    let r = unsafe { fp(device, info, &mut count, reps.as_mut_ptr()) };
    if r != vk::Result::SUCCESS && r != vk::Result::INCOMPLETE {
        return Err(GpuError::Vk {
            call: "vkGetPipelineExecutableInternalRepresentationsKHR",
            result: r,
        });
    }
    reps.truncate(count as usize);
    let mut buffers: Vec<Vec<u8>> = reps.iter().map(|r| vec![0u8; r.data_size]).collect();
    for (r, b) in reps.iter_mut().zip(buffers.iter_mut()) {
        r.p_data = b.as_mut_ptr() as *mut c_void;
    }
    // SAFETY: each struct points at a buffer of the size the driver asked for, alive for the call.
    unsafe { fp(device, info, &mut count, reps.as_mut_ptr()) }
        .result()
        .vk("vkGetPipelineExecutableInternalRepresentationsKHR")?;
    Ok(reps
        .iter()
        .zip(&buffers)
        .map(|(r, b)| {
            let data = b.get(..r.data_size).unwrap_or(b);
            let text = if r.is_text != 0 {
                CStr::from_bytes_until_nul(data)
                    .map(|c| c.to_string_lossy().into_owned())
                    .unwrap_or_else(|_| String::from_utf8_lossy(data).into_owned())
            } else {
                format!("({} bytes of binary data)", data.len())
            };
            (c_text(&r.name), text)
        })
        .collect())
}

impl Gpu {
    /// What every pipeline created from now on also asks of the driver. Errors, changing
    /// nothing, where the device cannot honour them (no VK_KHR_pipeline_executable_properties; a
    /// subgroup size outside `Caps::compute_subgroup_sizes`).
    pub fn set_compile_settings(&self, settings: CompileSettings) -> Result<()> {
        if let Some(why) = settings.unsupported(&self.inner.caps) {
            return Err(GpuError::Unsupported {
                device: self.inner.info.name.clone(),
                feature: why,
            });
        }
        let mut s = self
            .inner
            .compile
            .lock()
            .map_err(|_| GpuError::Other("compile settings lock poisoned".into()))?;
        *s = settings;
        Ok(())
    }

    pub fn compile_settings(&self) -> CompileSettings {
        self.inner.compile.lock().map(|s| *s).unwrap_or_default()
    }

    /// What every pipeline created with capture on reported since the last call, in creation
    /// order (so `ComputeDecl::build` and friends need no accessor to their pipelines).
    pub fn take_captured(&self) -> Vec<PipelineExecutables> {
        self.inner
            .captured
            .lock()
            .map(|mut c| std::mem::take(&mut *c))
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_names_join_merged_stages() {
        use vk::ShaderStageFlags as S;
        assert_eq!(stage_names(S::COMPUTE), "compute");
        assert_eq!(stage_names(S::VERTEX | S::GEOMETRY), "vertex+geometry");
        assert_eq!(stage_names(S::FRAGMENT), "fragment");
        assert_eq!(
            stage_names(S::MESH_EXT),
            format!("{:#x}", S::MESH_EXT.as_raw())
        );
    }

    #[test]
    fn settings_are_refused_where_the_device_cannot_honour_them() {
        let mut caps = crate::Caps::default();
        let stats = CompileSettings {
            statistics: true,
            ..Default::default()
        };
        let why = stats.unsupported(&caps).unwrap_or_default();
        assert!(
            why.contains("VK_KHR_pipeline_executable_properties"),
            "{why}"
        );
        caps.pipeline_executable_info = true;
        assert_eq!(stats.unsupported(&caps), None);
        caps.compute_subgroup_sizes = vec![64];
        let wave32 = CompileSettings {
            compute_subgroup_size: Some(32),
            ..Default::default()
        };
        let why = wave32.unsupported(&caps).unwrap_or_default();
        assert!(why.contains("subgroup size of 32"), "{why}");
        caps.compute_subgroup_sizes = vec![32, 64];
        assert_eq!(wave32.unsupported(&caps), None);
        assert_eq!(
            CompileSettings::default().flags(),
            vk::PipelineCreateFlags::empty()
        );
        let dis = CompileSettings {
            representations: true,
            ..Default::default()
        };
        assert_eq!(
            dis.flags(),
            vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
                | vk::PipelineCreateFlags::CAPTURE_INTERNAL_REPRESENTATIONS_KHR
        );
    }

    #[test]
    fn stats_serialize_as_ordered_objects() {
        let e = ExecutableStats {
            stage: "compute".into(),
            name: "main".into(),
            description: String::new(),
            subgroup_size: 64,
            stats: vec![
                ("VGPRs".into(), StatValue::U64(52)),
                ("SGPRs".into(), StatValue::U64(27)),
                ("Spilled".into(), StatValue::Bool(false)),
            ],
            representations: vec![],
        };
        let j = serde_json::to_string(&e).unwrap_or_default();
        assert!(
            j.contains(r#""stats":{"VGPRs":52,"SGPRs":27,"Spilled":false}"#),
            "{j}"
        );
        assert_eq!(e.stat("SGPRs"), Some(StatValue::U64(27)));
        assert_eq!(e.stat("sgprs"), None);
    }
}
