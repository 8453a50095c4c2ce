//! GLSL -> SPIR-V through shaderc (glslang), with `#include` and defines. Errors name file:line.
//! Compiled modules are cached by (path, stage, defines): sources are immutable for the life of a
//! `Shaders`, so that key identifies the whole include closure.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::error::{GpuError, Result};

/// Where shader sources come from: the binary's embedded copy of `shaders/`, or a folder.
pub trait SourceTree: Send + Sync {
    /// The text of `path` (relative to the shader root, `/`-separated), if it exists.
    fn read(&self, path: &str) -> Option<String>;
    /// Every source path in the tree, sorted (cache keys hash them all).
    fn list(&self) -> Vec<String>;
}

/// Sources read from a folder on disk (e.g. `CBR_SHADER_DIR` while editing shaders).
pub struct DirTree(pub PathBuf);

impl SourceTree for DirTree {
    fn read(&self, path: &str) -> Option<String> {
        std::fs::read_to_string(self.0.join(path)).ok()
    }

    fn list(&self) -> Vec<String> {
        fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
            let Ok(entries) = std::fs::read_dir(dir) else {
                return;
            };
            for e in entries.flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(root, &p, out);
                } else if let Ok(rel) = p.strip_prefix(root) {
                    out.push(normalise(rel));
                }
            }
        }
        let mut out = Vec::new();
        walk(&self.0, &self.0, &mut out);
        out.sort();
        out
    }
}

/// Sources compiled into the binary.
pub struct StaticTree(pub &'static [(&'static str, &'static str)]);

impl SourceTree for StaticTree {
    fn read(&self, path: &str) -> Option<String> {
        self.0
            .iter()
            .find(|(p, _)| *p == path)
            .map(|(_, s)| s.to_string())
    }

    fn list(&self) -> Vec<String> {
        let mut v: Vec<String> = self.0.iter().map(|(p, _)| p.to_string()).collect();
        v.sort();
        v
    }
}

type Key = (String, Vec<(String, String)>);

pub struct Shaders {
    sources: Box<dyn SourceTree>,
    cache: Mutex<HashMap<Key, Arc<Vec<u32>>>>,
    /// Every (path, defines) asked for, in order (what a pipeline was built from).
    requests: Mutex<Vec<Key>>,
}

/// A compile request: path and sorted defines.
pub type Request = (String, Vec<(String, String)>);

/// The words of a SPIR-V module without its debug instructions (OpSource, OpSourceContinued,
/// OpSourceExtension, OpName, OpMemberName, OpString, OpLine, OpNoLine, OpModuleProcessed) and
/// without the header's ID bound: what the module computes, unchanged by comments, line shifts
/// or code in branches its defines exclude. Frame caches key on it.
/// The (set, binding) pairs of the descriptors a SPIR-V module's entry points reference: from
/// SPIR-V 1.4 on, an `OpEntryPoint` lists every global variable its call tree uses, so a binding
/// that the preprocessor or the optimiser removed from the code is absent. `None` for older
/// modules (whose entry points list only inputs and outputs) or words that do not parse.
pub fn referenced_bindings(spirv: &[u32]) -> Option<std::collections::BTreeSet<(u32, u32)>> {
    const MAGIC: u32 = 0x0723_0203;
    const OP_ENTRY_POINT: u32 = 15;
    const OP_DECORATE: u32 = 71;
    const BINDING: u32 = 33;
    const DESCRIPTOR_SET: u32 = 34;
    if spirv.len() < 5 || spirv[0] != MAGIC || spirv[1] < 0x0001_0400 {
        return None;
    }
    let mut interface = std::collections::BTreeSet::new();
    let mut binding = std::collections::BTreeMap::new();
    let mut set = std::collections::BTreeMap::new();
    let mut i = 5;
    while i < spirv.len() {
        let (count, op) = ((spirv[i] >> 16) as usize, spirv[i] & 0xffff);
        if count == 0 || i + count > spirv.len() {
            return None;
        }
        let w = &spirv[i..i + count];
        match op {
            OP_ENTRY_POINT if count >= 3 => {
                // Execution model, id, a nul-terminated name in words, then the interface ids.
                let name_words = w[3..].iter().position(|x| x.to_le_bytes().contains(&0))? + 1;
                interface.extend(w[3 + name_words..].iter().copied());
            }
            OP_DECORATE if count == 4 && w[2] == BINDING => {
                binding.insert(w[1], w[3]);
            }
            OP_DECORATE if count == 4 && w[2] == DESCRIPTOR_SET => {
                set.insert(w[1], w[3]);
            }
            _ => {}
        }
        i += count;
    }
    Some(
        binding
            .iter()
            .filter(|(id, _)| interface.contains(*id))
            .map(|(id, b)| (set.get(id).copied().unwrap_or(0), *b))
            .collect(),
    )
}

pub fn semantic_words(spirv: &[u32]) -> Vec<u32> {
    const DEBUG: [u32; 9] = [2, 3, 4, 5, 6, 7, 8, 317, 330];
    let mut out = Vec::with_capacity(spirv.len());
    if spirv.len() < 5 {
        return spirv.to_vec();
    }
    // Header: magic, version, generator, bound (skipped), schema.
    out.extend_from_slice(&[spirv[0], spirv[1], spirv[2], spirv[4]]);
    let mut i = 5;
    while i < spirv.len() {
        let count = (spirv[i] >> 16) as usize;
        let opcode = spirv[i] & 0xffff;
        if count == 0 || i + count > spirv.len() {
            out.extend_from_slice(&spirv[i..]);
            break;
        }
        if !DEBUG.contains(&opcode) {
            out.extend_from_slice(&spirv[i..i + count]);
        }
        i += count;
    }
    out
}

fn normalise(p: &Path) -> String {
    let mut out: Vec<String> = Vec::new();
    for c in p.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(s) => out.push(s.to_string_lossy().into_owned()),
            _ => {}
        }
    }
    out.join("/")
}

impl Shaders {
    pub fn new(sources: Box<dyn SourceTree>) -> Shaders {
        Shaders {
            sources,
            cache: Mutex::new(HashMap::new()),
            requests: Mutex::new(Vec::new()),
        }
    }

    /// How many compile requests were made so far (a mark for [`Shaders::requests_since`]).
    pub fn request_mark(&self) -> usize {
        self.requests.lock().map(|r| r.len()).unwrap_or(0)
    }

    /// The distinct (path, defines) requested since `mark`, sorted: the modules the pipelines
    /// built in between use.
    pub fn requests_since(&self, mark: usize) -> Vec<Request> {
        let mut v: Vec<Request> = self
            .requests
            .lock()
            .map(|r| r.get(mark..).unwrap_or(&[]).to_vec())
            .unwrap_or_default();
        v.sort();
        v.dedup();
        v
    }

    /// Every (path, text) of the source tree, sorted by path.
    pub fn sources(&self) -> Vec<(String, String)> {
        self.sources
            .list()
            .into_iter()
            .filter_map(|p| self.sources.read(&p).map(|t| (p, t)))
            .collect()
    }

    /// Compiles `path` (stage from its extension: .vert .geom .frag .comp) with `defines`.
    pub fn compile(&self, path: &str, defines: &[(String, String)]) -> Result<Arc<Vec<u32>>> {
        let mut defs = defines.to_vec();
        defs.sort();
        let key = (path.to_string(), defs.clone());
        if let Ok(mut r) = self.requests.lock() {
            r.push(key.clone());
        }
        if let Some(hit) = self.cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return Ok(hit);
        }
        let kind = match Path::new(path).extension().and_then(|e| e.to_str()) {
            Some("vert") => shaderc::ShaderKind::Vertex,
            Some("frag") => shaderc::ShaderKind::Fragment,
            Some("geom") => shaderc::ShaderKind::Geometry,
            Some("comp") => shaderc::ShaderKind::Compute,
            _ => {
                return Err(GpuError::Shader {
                    file: path.into(),
                    message: "unknown shader stage (expected .vert, .geom, .frag or .comp)".into(),
                });
            }
        };
        let source = self
            .sources
            .read(path)
            .ok_or_else(|| GpuError::ShaderNotFound(PathBuf::from(path)))?;
        let compiler = shaderc::Compiler::new().map_err(|e| GpuError::Shader {
            file: path.into(),
            message: format!("shaderc unavailable: {e}"),
        })?;
        let mut opts = shaderc::CompileOptions::new().map_err(|e| GpuError::Shader {
            file: path.into(),
            message: format!("shaderc options: {e}"),
        })?;
        // Vulkan 1.2 SPIR-V: 1.3 would emit LocalSizeId, which needs maintenance4 (PLATFORM.md).
        opts.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_2 as u32,
        );
        opts.set_optimization_level(shaderc::OptimizationLevel::Performance);
        opts.set_generate_debug_info();
        for (k, v) in &defs {
            opts.add_macro_definition(k, Some(v));
        }
        let sources = &self.sources;
        opts.set_include_callback(move |requested, ty, requesting, _depth| {
            let candidates = match ty {
                shaderc::IncludeType::Relative => {
                    let dir = Path::new(requesting).parent().unwrap_or(Path::new(""));
                    vec![
                        normalise(&dir.join(requested)),
                        normalise(Path::new(requested)),
                    ]
                }
                shaderc::IncludeType::Standard => vec![normalise(Path::new(requested))],
            };
            candidates
                .iter()
                .find_map(|c| sources.read(c).map(|text| (c.clone(), text)))
                .map(|(name, content)| shaderc::ResolvedInclude {
                    resolved_name: name,
                    content,
                })
                .ok_or_else(|| format!("cannot find include `{requested}` (from {requesting})"))
        });
        let art = compiler
            .compile_into_spirv(&source, kind, path, "main", Some(&opts))
            .map_err(|e| GpuError::Shader {
                file: path.into(),
                message: compile_message(e),
            })?;
        let words = Arc::new(art.as_binary().to_vec());
        if let Ok(mut c) = self.cache.lock() {
            c.insert(key, words.clone());
        }
        Ok(words)
    }
}

fn compile_message(e: shaderc::Error) -> String {
    match e {
        shaderc::Error::CompilationError(_, msg) => msg.trim_end().to_string(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TREE: &[(&str, &str)] = &[
        (
            "inc/common.glsl",
            "#define ONE 1.0\nfloat helper() { return ONE; }\n",
        ),
        (
            "pass/ok.comp",
            "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"../inc/common.glsl\"\nlayout(local_size_x = 8) in;\nlayout(std430, binding = 0) buffer B { float v[]; };\nvoid main() { v[gl_GlobalInvocationID.x] = helper() * SCALE; }\n",
        ),
        (
            "pass/broken.frag",
            "#version 460\nvoid main() {\n  float x = undefined_thing;\n}\n",
        ),
        (
            "pass/missing_inc.frag",
            "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include <nope.glsl>\nvoid main() {}\n",
        ),
    ];

    fn shaders() -> Shaders {
        Shaders::new(Box::new(StaticTree(TREE)))
    }

    #[test]
    fn compiles_with_includes_and_defines() {
        let s = shaders();
        let words = s
            .compile("pass/ok.comp", &[("SCALE".into(), "2.0".into())])
            .expect("compiles");
        assert_eq!(words[0], 0x0723_0203, "SPIR-V magic");
        let again = s
            .compile("pass/ok.comp", &[("SCALE".into(), "2.0".into())])
            .expect("cached");
        assert!(
            Arc::ptr_eq(&words, &again),
            "second compile comes from the cache"
        );
        let other = s
            .compile("pass/ok.comp", &[("SCALE".into(), "3.0".into())])
            .expect("compiles");
        assert!(!Arc::ptr_eq(&words, &other), "defines are part of the key");
    }

    #[test]
    fn errors_name_file_and_line() {
        let err = shaders()
            .compile("pass/broken.frag", &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("pass/broken.frag:3"), "{err}");
        assert!(err.contains("undefined_thing"), "{err}");
        let err = shaders()
            .compile("pass/missing_inc.frag", &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope.glsl"), "{err}");
        let err = shaders()
            .compile("pass/absent.frag", &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("absent.frag"), "{err}");
    }
}
