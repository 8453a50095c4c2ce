//! OBJ/MTL through tobj, hardened against what real files do.
//!
//! tobj gives no line numbers and panics on some malformed MTL lines, so a validating pre-pass reads
//! every statement cbr relies on first (and reports `file:line`); the normalised text (LF line ends,
//! faces with fewer than three vertices removed, one-value colours expanded) then goes to tobj.

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use crate::error::{Result, SceneError};
use crate::files::{Disk, Files};
use crate::scene::{AlphaSource, LoadStats, Material, Object, Up, Vertex};
use crate::texture::Texture;

/// What to do when a texture file named by an MTL is missing or unreadable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MissingTextures {
    /// Fail, naming the texture and the MTL (default).
    #[default]
    Error,
    /// Substitute a magenta checker and record a warning.
    Fallback,
}

#[derive(Clone, Debug, Default)]
pub struct ObjOptions {
    /// Use this MTL instead of the OBJ's `mtllib` (paths inside it are relative to it).
    pub mtl_override: Option<PathBuf>,
    /// Material for faces without `usemtl` (by name, from the MTL).
    pub default_material: Option<String>,
    pub missing_textures: MissingTextures,
    pub up: Up,
}

/// Geometry, materials and textures read from one OBJ, ready to append to a scene.
pub struct ObjData {
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub stats: LoadStats,
}

fn read_text(files: &dyn Files, path: &Path) -> Result<String> {
    let bytes = files
        .read(path)
        .map_err(|e| SceneError::file(path, format!("cannot read: {e}")))?;
    // Real files carry Latin-1 names; decode lossily and normalise line ends.
    Ok(String::from_utf8_lossy(&bytes)
        .replace("\r\n", "\n")
        .replace('\r', "\n"))
}

/// A finite number (`T`: f32, or f64 for vertex coordinates), or an error naming `what` and the line.
fn parse_finite<T: std::str::FromStr + Into<f64> + Copy>(
    tok: Option<&str>,
    file: &Path,
    line: usize,
    what: &str,
) -> Result<T> {
    let tok =
        tok.ok_or_else(|| SceneError::syntax(file, line, format!("{what}: missing number")))?;
    let v: T = tok
        .parse()
        .map_err(|_| SceneError::syntax(file, line, format!("{what}: `{tok}` is not a number")))?;
    if !v.into().is_finite() {
        return Err(SceneError::syntax(
            file,
            line,
            format!("{what}: `{tok}` is not a finite number"),
        ));
    }
    Ok(v)
}

/// A vertex coordinate, read in double precision as tobj reads it (`use_f64`): finite and within
/// [`crate::MAX_COORDINATE`], where an f64 still resolves a millimetre.
fn parse_coordinate(tok: Option<&str>, file: &Path, line: usize, what: &str) -> Result<f64> {
    let v = parse_finite::<f64>(tok, file, line, what)?;
    crate::check_coordinate(v)
        .map_err(|e| SceneError::syntax(file, line, format!("{what}: {e}")))?;
    Ok(v)
}

/// What the pre-pass counted.
#[derive(Debug, Default, PartialEq, Eq)]
pub(crate) struct ObjCounts {
    /// Faces with fewer than three vertices, removed.
    pub dropped: usize,
    /// Faces without texture coordinates (they sample UV (0,0)).
    pub faces_without_uvs: usize,
}

/// Validates the OBJ statements cbr uses and returns the normalised text.
///
/// tobj gives a face without `vt` texture coordinate 0 when the file has other UVs, so when the
/// file has any `vt`, a sentinel `vt 0 1` (UV (0,0) after the V flip) is prepended, positive `vt`
/// references shift by one, and faces without UVs point at the sentinel.
pub(crate) fn validate_obj(text: &str, file: &Path) -> Result<(String, ObjCounts)> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    let mut out = String::with_capacity(text.len() + 64);
    let mut counts = ObjCounts::default();
    let sentinel = text.lines().any(|l| l.trim_start().starts_with("vt "));
    if sentinel {
        out.push_str("vt 0 1\n");
    }
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let line = raw.split('#').next().unwrap_or("");
        let mut toks = line.split_whitespace();
        match toks.next() {
            Some("v") => {
                for axis in ["x", "y", "z"] {
                    parse_coordinate(toks.next(), file, ln, &format!("vertex {axis}"))?;
                }
                nv += 1;
            }
            Some("vt") => {
                for axis in ["u", "v"] {
                    // A lone `vt u` is legal (v = 0).
                    if axis == "v" && toks.clone().next().is_none() {
                        break;
                    }
                    parse_finite::<f32>(
                        toks.next(),
                        file,
                        ln,
                        &format!("texture coordinate {axis}"),
                    )?;
                }
                nt += 1;
            }
            Some("vn") => {
                for axis in ["x", "y", "z"] {
                    parse_finite::<f32>(toks.next(), file, ln, &format!("normal {axis}"))?;
                }
                nn += 1;
            }
            Some("f") => {
                let refs: Vec<&str> = toks.collect();
                for r in &refs {
                    let mut parts = r.split('/');
                    for (k, (count, what)) in
                        [(nv, "vertex"), (nt, "texture coordinate"), (nn, "normal")]
                            .into_iter()
                            .enumerate()
                    {
                        let Some(p) = parts.next() else { break };
                        if p.is_empty() && k > 0 {
                            continue;
                        }
                        let idx: i64 = p.parse().map_err(|_| {
                            SceneError::syntax(
                                file,
                                ln,
                                format!("face: `{r}` is not a valid vertex reference"),
                            )
                        })?;
                        let resolved = if idx < 0 { count + idx + 1 } else { idx };
                        if idx == 0 || resolved < 1 || resolved > count {
                            return Err(SceneError::syntax(
                                file,
                                ln,
                                format!(
                                    "face refers to {what} {idx}, but {count} are defined before this line"
                                ),
                            ));
                        }
                    }
                }
                if refs.len() < 3 {
                    counts.dropped += 1;
                    out.push('\n');
                    continue;
                }
                let missing_uv = refs
                    .iter()
                    .any(|r| r.split('/').nth(1).is_none_or(str::is_empty));
                if missing_uv {
                    counts.faces_without_uvs += 1;
                }
                if sentinel {
                    out.push('f');
                    for r in &refs {
                        let parts: Vec<&str> = r.split('/').collect();
                        let vt = match parts.get(1) {
                            Some(t) if !t.is_empty() => match t.parse::<i64>() {
                                Ok(i) if i > 0 => (i + 1).to_string(),
                                _ => t.to_string(),
                            },
                            _ => "1".to_string(),
                        };
                        let vn = parts
                            .get(2)
                            .filter(|n| !n.is_empty())
                            .map(|n| format!("/{n}"))
                            .unwrap_or_default();
                        out.push_str(&format!(" {}/{vt}{vn}", parts[0]));
                    }
                    out.push('\n');
                    continue;
                }
            }
            _ => {}
        }
        out.push_str(raw);
        out.push('\n');
    }
    Ok((out, counts))
}

/// Validates an MTL (tobj panics on short colour lines) and returns normalised text.
pub(crate) fn validate_mtl(text: &str, file: &Path) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut toks = line.split_whitespace();
        let key = toks.next();
        match key {
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) => {
                let vals: Vec<&str> = toks.collect();
                let nums = vals
                    .iter()
                    .map(|t| parse_finite(Some(t), file, ln, k))
                    .collect::<Result<Vec<f32>>>()?;
                match nums.len() {
                    1 => {
                        out.push_str(&format!("{k} {0} {0} {0}\n", nums[0]));
                        continue;
                    }
                    n if n >= 3 => {}
                    n => {
                        return Err(SceneError::syntax(
                            file,
                            ln,
                            format!("{k} needs 3 numbers, found {n}"),
                        ));
                    }
                }
                out.push_str(&format!("{k} {} {} {}\n", nums[0], nums[1], nums[2]));
                continue;
            }
            Some(k @ ("Ns" | "Ni" | "d")) => {
                parse_finite::<f32>(toks.next(), file, ln, k)?;
            }
            Some("newmtl") if toks.next().is_none() => {
                return Err(SceneError::syntax(file, ln, "newmtl without a name"));
            }
            Some(k)
                if (k.starts_with("map_") || k == "bump" || k == "disp" || k == "decal")
                    && toks.next().is_none() =>
            {
                return Err(SceneError::syntax(
                    file,
                    ln,
                    format!("{k} without a file name"),
                ));
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(out)
}

/// The file name of a texture statement (`map_Kd -bm 0.5 dir\\file.png`): the last word, with
/// Windows separators normalised; plus the `-bm` bump multiplier if present.
fn texture_ref(spec: &str) -> (String, Option<f32>) {
    let words: Vec<&str> = spec.split_whitespace().collect();
    let bm = words
        .windows(2)
        .find(|w| w[0] == "-bm")
        .and_then(|w| w[1].parse().ok());
    let name = words.last().copied().unwrap_or("").replace('\\', "/");
    (name, bm)
}

struct TextureCache<'a> {
    files: &'a dyn Files,
    textures: Vec<Texture>,
    index: HashMap<(PathBuf, bool), u32>,
    missing: MissingTextures,
    stats: &'a mut LoadStats,
}

impl TextureCache<'_> {
    fn get(&mut self, path: &Path, srgb: bool, mtl: &Path, material: &str) -> Result<u32> {
        let key = (path.to_path_buf(), srgb);
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        let loaded = self
            .files
            .read(path)
            .map_err(|e| crate::texture::read_error(path, &e))
            .and_then(|bytes| Texture::decode(path, &bytes, srgb));
        let tex = match loaded {
            Ok(t) => t,
            Err(e) if self.missing == MissingTextures::Fallback => {
                self.stats.warnings.push(format!(
                    "{e} (material `{material}` in {}); using the fallback checker",
                    mtl.display()
                ));
                self.stats.fallback_textures += 1;
                Texture::fallback(&path.to_string_lossy())
            }
            Err(e) => {
                // `e` names the texture already: add where it was named, not the path again.
                let why = match e {
                    SceneError::File { msg, .. } => msg,
                    other => other.to_string(),
                };
                return Err(SceneError::file(
                    path,
                    format!(
                        "{why} (named by material `{material}` in {}); pass --missing-textures fallback to render anyway",
                        mtl.display()
                    ),
                ));
            }
        };
        let i = self.textures.len() as u32;
        self.textures.push(tex);
        self.index.insert(key, i);
        Ok(i)
    }
}

fn convert_material(m: &tobj::Material, mtl: &Path, cache: &mut TextureCache) -> Result<Material> {
    let dir = mtl.parent().unwrap_or(Path::new("."));
    let mut out = Material::named(&m.name);
    // tobj reads every number in f64 (`use_f64`, for vertex positions); materials stay f32.
    let f32x3 = |c: [f64; 3]| c.map(|v| v as f32);
    if let Some(kd) = m.diffuse {
        out.kd = f32x3(kd);
    }
    if let Some(ks) = m.specular {
        out.ks = f32x3(ks);
    }
    if let Some(ns) = m.shininess {
        out.ns = (ns as f32).max(1.0);
    }
    if let Some(ke) = m.emissive {
        out.ke = f32x3(ke);
    }
    if let Some(t) = &m.diffuse_texture {
        let (name, _) = texture_ref(t);
        let tex = cache.get(&dir.join(&name), true, mtl, &m.name)?;
        out.kd_tex = Some(tex);
        // Textured materials take their colour from the texture (scaled by Kd).
        if cache.textures[tex as usize].has_alpha {
            out.alpha = AlphaSource::Texture { tex, channel: 3 };
        }
    }
    if let Some(t) = &m.dissolve_texture {
        let (name, _) = texture_ref(t);
        let path = dir.join(&name);
        // The same file as map_Kd: its alpha channel is the mask (sRGB does not touch alpha).
        let same_as_kd = m
            .diffuse_texture
            .as_ref()
            .map(|d| dir.join(texture_ref(d).0))
            == Some(path.clone());
        let tex = cache.get(&path, same_as_kd, mtl, &m.name)?;
        let channel = if cache.textures[tex as usize].has_alpha {
            3
        } else {
            0
        };
        out.alpha = AlphaSource::Texture { tex, channel };
    }
    if let Some(t) = &m.normal_texture {
        let (name, bm) = texture_ref(t);
        out.bump_tex = Some(cache.get(&dir.join(&name), false, mtl, &m.name)?);
        out.bump_scale = bm.unwrap_or(1.0);
    }
    Ok(out)
}

type MtlLib = <tobj::MTLLoadResult as IntoIterator>::Item;

fn load_mtl(files: &dyn Files, path: &Path) -> Result<MtlLib> {
    let text = validate_mtl(&read_text(files, path)?, path)?;
    tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes()))
        .map_err(|e| SceneError::file(path, format!("cannot parse MTL: {e}")))
}

/// Loads an OBJ with its materials and textures from the file system.
pub fn load_obj(path: &Path, opts: &ObjOptions) -> Result<ObjData> {
    load_obj_from(&Disk, path, opts)
}

/// Loads an OBJ with its materials and textures from `files` (the file system is [`Disk`]; tests
/// and the fuzzer pass [`crate::files::MemoryFiles`]).
pub fn load_obj_from(files: &dyn Files, path: &Path, opts: &ObjOptions) -> Result<ObjData> {
    let text = read_text(files, path)?;
    let (text, counts) = validate_obj(&text, path)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut stats = LoadStats {
        dropped_faces: counts.dropped,
        faces_without_uvs: counts.faces_without_uvs,
        ..Default::default()
    };

    // Materials in tobj's order (material_id indexes this list), with the file each came from.
    let mtls: RefCell<Vec<(tobj::Material, PathBuf)>> = RefCell::new(Vec::new());
    let warnings: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let load_opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let loaded = tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &load_opts, |requested| {
        let named = dir.join(requested.to_string_lossy().replace('\\', "/"));
        let chosen = if let Some(o) = &opts.mtl_override {
            if !mtls.borrow().is_empty() {
                return Ok((Vec::new(), Default::default()));
            }
            o.clone()
        } else if files.is_file(&named) {
            named
        } else {
            let guess = path.with_extension("mtl");
            if files.is_file(&guess) {
                warnings.borrow_mut().push(format!(
                    "{}: mtllib `{}` not found; using {} instead",
                    path.display(),
                    requested.display(),
                    guess.display()
                ));
                guess
            } else {
                warnings.borrow_mut().push(format!(
                    "{}: mtllib `{}` not found; faces use the default material",
                    path.display(),
                    requested.display()
                ));
                return Ok((Vec::new(), Default::default()));
            }
        };
        match load_mtl(files, &chosen) {
            Ok((mats, names)) => {
                let mut list = mtls.borrow_mut();
                list.extend(mats.iter().cloned().map(|m| (m, chosen.clone())));
                // tobj resolves `usemtl` through this name -> index map (it offsets it itself).
                Ok((mats, names))
            }
            Err(e) => {
                *mtl_error.borrow_mut() = Some(e);
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, _) =
        loaded.map_err(|e| SceneError::file(path, format!("cannot parse OBJ: {e}")))?;
    stats.warnings.extend(warnings.into_inner());
    let mut mtls = mtls.into_inner();
    if mtls.is_empty()
        && let Some(o) = &opts.mtl_override
    {
        mtls.extend(load_mtl(files, o)?.0.into_iter().map(|m| (m, o.clone())));
    }

    let mut cache = TextureCache {
        files,
        textures: Vec::new(),
        index: HashMap::new(),
        missing: opts.missing_textures,
        stats: &mut stats,
    };
    let mut materials = Vec::with_capacity(mtls.len() + 1);
    for (m, file) in &mtls {
        materials.push(convert_material(m, file, &mut cache)?);
    }
    let textures = cache.textures;
    let default_material = match &opts.default_material {
        Some(name) => materials
            .iter()
            .position(|m| &m.name == name)
            .ok_or_else(|| {
                SceneError::file(
                    path,
                    format!("default material `{name}` is not defined by the MTL"),
                )
            })?,
        None => {
            materials.push(Material::named("default"));
            materials.len() - 1
        }
    };

    let mut objects = Vec::with_capacity(models.len());
    for model in &models {
        let material = model.mesh.material_id.unwrap_or(default_material) as u32;
        let mut model = model.clone();
        if model.name == "unnamed_object" {
            // tobj's name for geometry before any `o`/`g`: use the file's name instead.
            model.name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        if let Some(obj) = build_object(&model, material, opts.up, &mut stats) {
            objects.push(obj);
        }
    }
    if objects.is_empty() {
        return Err(SceneError::file(path, "no drawable triangles"));
    }
    Ok(ObjData {
        objects,
        materials,
        textures,
        stats,
    })
}

/// The largest magnitude of an object's coordinates at which its vertices stay absolute (origin 0)
/// whatever its size: 2^10 m, where an f32 steps by 2^-13 m (0.12 mm). Beyond it, see [`recentre`].
pub const RECENTRE_BEYOND_M: f64 = 1024.0;

/// How many times its half-size an object must lie from the origin to be recentred below
/// [`RECENTRE_BEYOND_M`]: 128, seven bits of its f32 vertices' 24.
pub const RECENTRE_RATIO: f64 = 128.0;

/// Where an object whose positions span `min`..`max` (f64, world) keeps its local origin: the
/// centre of its bounds where that makes its f32 vertices meaningfully finer, the world origin
/// otherwise. Meaningfully: the farthest coordinate is at least [`RECENTRE_RATIO`] times the
/// object's half-size (it gains at least seven bits), or it is beyond [`RECENTRE_BEYOND_M`] and at
/// least twice the half-size (it gains at least a bit where an f32 steps by 0.12 mm or more).
///
/// Objects near the origin keep origin 0 and the f32 vertices they always had, so every scene
/// that loaded before keeps its bits (the shared scenes reach 740 m, Panda3D's environment, and at
/// most 34 times an object's half-size); a mesh exported in world coordinates far away (a
/// georeferenced city model, CAD or survey data) is stored about its own centre, in f64.
pub fn recentre(min: DVec3, max: DVec3) -> DVec3 {
    let far = min.abs().max(max.abs()).max_element();
    let half = ((max - min) * 0.5).max_element();
    if far >= RECENTRE_RATIO * half || (far > RECENTRE_BEYOND_M && far >= 2.0 * half) {
        (min + max) * 0.5
    } else {
        DVec3::ZERO
    }
}

fn build_object(
    model: &tobj::Model,
    material: u32,
    up: Up,
    stats: &mut LoadStats,
) -> Option<Object> {
    let m = &model.mesh;
    // Positions in f64 (world), then in f32 about the object's origin: what is rendered.
    let world: Vec<DVec3> = m
        .positions
        .chunks_exact(3)
        .map(|p| DVec3::from(up.to_y_up([p[0], p[1], p[2]])))
        .collect();
    let (lo, hi) = world.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let origin = if world.is_empty() {
        DVec3::ZERO
    } else {
        recentre(lo, hi)
    };
    let local: Vec<Vec3> = world.iter().map(|&p| (p - origin).as_vec3()).collect();
    let pos = |i: u32| -> Vec3 { local[i as usize] };
    let has_normals = !m.normals.is_empty() && m.normal_indices.len() == m.indices.len();
    let has_uvs = !m.texcoords.is_empty() && m.texcoord_indices.len() == m.indices.len();
    // Keep only triangles with three distinct corners.
    let tris: Vec<usize> = (0..m.indices.len() / 3)
        .filter(|&t| {
            let [a, b, c] = [m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]];
            let ok = a != b
                && b != c
                && a != c
                && pos(a) != pos(b)
                && pos(b) != pos(c)
                && pos(a) != pos(c);
            if !ok {
                stats.dropped_faces += 1;
            }
            ok
        })
        .collect();
    if tris.is_empty() {
        return None;
    }
    // Smooth normals per position index (area-weighted), for meshes without normals.
    let smooth: Vec<Vec3> = if has_normals {
        Vec::new()
    } else {
        stats.computed_normals += 1;
        let mut acc = vec![Vec3::ZERO; m.positions.len() / 3];
        for &t in &tris {
            let [a, b, c] = [m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]];
            let n = (pos(b) - pos(a)).cross(pos(c) - pos(a));
            for i in [a, b, c] {
                acc[i as usize] += n;
            }
        }
        acc.into_iter().map(|n| n.normalize_or_zero()).collect()
    };
    let mut remap: HashMap<(u32, u32, u32), u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut indices = Vec::with_capacity(tris.len() * 3);
    for &t in &tris {
        let face_n = {
            let [a, b, c] = [m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]];
            (pos(b) - pos(a)).cross(pos(c) - pos(a)).normalize_or_zero()
        };
        for k in 3 * t..3 * t + 3 {
            let p = m.indices[k];
            let n = if has_normals {
                m.normal_indices[k]
            } else {
                u32::MAX
            };
            let uv = if has_uvs {
                m.texcoord_indices[k]
            } else {
                u32::MAX
            };
            let next = vertices.len() as u32;
            let idx = *remap.entry((p, n, uv)).or_insert_with(|| {
                let normal = if has_normals {
                    let j = n as usize * 3;
                    let n = [m.normals[j], m.normals[j + 1], m.normals[j + 2]].map(|v| v as f32);
                    Vec3::from(up.to_y_up(n)).normalize_or_zero()
                } else {
                    smooth[p as usize]
                };
                let normal = if normal == Vec3::ZERO || !normal.is_finite() {
                    face_n
                } else {
                    normal
                };
                let uv = if has_uvs {
                    let j = uv as usize * 2;
                    [
                        m.texcoords[j] as f32,
                        1.0 - m.texcoords.get(j + 1).map_or(0.0, |&v| v as f32),
                    ]
                } else {
                    [0.0, 0.0]
                };
                vertices.push(Vertex {
                    pos: pos(p).to_array(),
                    normal: normal.to_array(),
                    uv,
                });
                next
            });
            indices.push(idx);
        }
    }
    stats.triangles += tris.len();
    Some(Object {
        name: model.name.clone(),
        vertices,
        indices,
        material,
        origin: origin.to_array(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f() -> PathBuf {
        PathBuf::from("t.obj")
    }

    #[test]
    fn nan_vertex_names_the_line() {
        let err = validate_obj("v 0 0 0\nv 1 nan 0\n", &f())
            .unwrap_err()
            .to_string();
        assert_eq!(err, "t.obj:2: vertex y: `nan` is not a finite number");
        let err = validate_obj("v 0 0 inf\n", &f()).unwrap_err().to_string();
        assert!(err.starts_with("t.obj:1: vertex z"), "{err}");
        let err = validate_obj("v 0 0\n", &f()).unwrap_err().to_string();
        assert!(err.contains("t.obj:1: vertex z: missing number"), "{err}");
    }

    #[test]
    fn coordinates_f64_cannot_hold_to_a_millimetre_name_the_line() {
        // Read as f64, 1e39 (past f32's range) is finite, and refused as beyond 2^43 m.
        let err = validate_obj("v 1e39 0 0\n", &f()).unwrap_err().to_string();
        assert!(
            err.contains("vertex x: the coordinate 1e39 is beyond"),
            "{err}"
        );
        assert!(validate_obj("v 8796093022207 0 -1e7\n", &f()).is_ok());
        let err = validate_obj("v 0 0 0\nv 0 -8796093022208 0\n", &f())
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("t.obj:2: vertex y: the coordinate -8.796093022208e12 is beyond what f64 holds at 1 mm precision"),
            "{err}"
        );
        let err = validate_obj("v 0 0 1e400\n", &f()).unwrap_err().to_string();
        assert_eq!(err, "t.obj:1: vertex z: `1e400` is not a finite number");
    }

    fn load_far(d: f64) -> ObjData {
        let files = crate::cases::far_obj(d);
        load_obj_from(&files, Path::new("far/far.obj"), &ObjOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// The same mesh (`cases::far_obj`) written 1 km to 10,000 km from the origin loads about its
    /// own centre: the f64 origin is the bounds' centre, and every vertex (origin + f32 local) lies
    /// within 1e-6 m of the origin copy's moved by the distance, with its normal (computed ones
    /// within 1e-6) and UV. Read in f32, the file's coordinates are up to 0.5 m off at 10,000 km.
    #[test]
    fn far_coordinates_in_the_file_are_recentred_in_f64() {
        let near = load_far(0.0);
        for o in &near.objects {
            assert_eq!(o.origin, [0.0; 3], "{}: near the origin, absolute", o.name);
        }
        let world = |o: &Object, v: &Vertex| DVec3::from(o.origin) + Vec3::from(v.pos).as_dvec3();
        for d in [1e3, 1e5, 1e6, 1e7] {
            let away = load_far(d);
            assert_eq!(away.objects.len(), near.objects.len());
            for (a, n) in away.objects.iter().zip(&near.objects) {
                let b = crate::scene::bounds_of(std::slice::from_ref(n));
                let want = b.center() + DVec3::new(d, 0.0, d);
                assert!(
                    (DVec3::from(a.origin) - want).length() < 1e-9 * d,
                    "{} at {d:e} m: origin {:?}, bounds centre {want}",
                    a.name,
                    a.origin
                );
                assert_eq!(a.indices, n.indices);
                for (va, vn) in a.vertices.iter().zip(&n.vertices) {
                    let err = (world(a, va) - world(n, vn) - DVec3::new(d, 0.0, d)).length();
                    assert!(err < 1e-6, "{} at {d:e} m: a vertex {err:e} m off", a.name);
                    assert!(Vec3::from(va.pos).length() < 5.0, "{}: local", a.name);
                    assert_eq!(va.uv, vn.uv);
                    let dn = (Vec3::from(va.normal) - Vec3::from(vn.normal)).length();
                    assert!(dn < 1e-6, "{}: normal {dn:e} off", a.name);
                }
            }
        }
    }

    #[test]
    fn recentring_is_kept_for_where_it_gains_precision() {
        let r = |lo: [f64; 3], hi: [f64; 3]| recentre(DVec3::from(lo), DVec3::from(hi));
        // Near the origin: absolute, whatever the shape (Sibenik's 20 m, Panda3D's 740 m terrain,
        // a 7 m rock 245 m out).
        assert_eq!(r([-20.0, -2.0, -8.0], [20.0, 15.0, 8.0]), DVec3::ZERO);
        assert_eq!(r([-739.0, -5.0, -600.0], [700.0, 40.0, 650.0]), DVec3::ZERO);
        assert_eq!(r([231.0, 0.0, 40.0], [245.6, 9.0, 50.0]), DVec3::ZERO);
        // Far against its size: recentred.
        assert_eq!(
            r([997.0, 0.0, 994.0], [1003.0, 2.0, 1000.0]),
            DVec3::new(1000.0, 1.0, 997.0)
        );
        // Beyond 1,024 m and at least twice its half-size: recentred; a terrain about the origin
        // gains nothing and stays absolute.
        assert_eq!(
            r([1500.0, 0.0, 0.0], [2500.0, 10.0, 10.0]),
            DVec3::new(2000.0, 5.0, 5.0)
        );
        assert_eq!(
            r([-1500.0, 0.0, -1500.0], [1500.0, 10.0, 1500.0]),
            DVec3::ZERO
        );
    }

    #[test]
    fn face_indices_are_checked_with_negative_ones_resolved() {
        let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1/1 2/1 3/1\n";
        assert!(validate_obj(ok, &f()).is_err(), "vt 1 is not defined");
        let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf -3 -2 -1\nf 1/1 2/1 3/1\nf 1//1 2//1 3//1\n";
        let err = validate_obj(ok, &f()).unwrap_err().to_string();
        assert!(
            err.contains("t.obj:7: face refers to normal 1, but 0 are defined"),
            "{err}"
        );
        let err = validate_obj("v 0 0 0\nf 1 2 3\n", &f())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("t.obj:2: face refers to vertex 2, but 1 are defined"),
            "{err}"
        );
        let err = validate_obj("v 0 0 0\nf 1 x 1\n", &f())
            .unwrap_err()
            .to_string();
        assert!(err.contains("`x` is not a valid vertex reference"), "{err}");
    }

    #[test]
    fn short_faces_are_dropped_and_counted() {
        let (text, counts) = validate_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", &f()).expect("valid");
        assert_eq!(counts.dropped, 1);
        assert!(!text.contains("f 1 2"));
    }

    #[test]
    fn faces_without_uvs_point_at_the_sentinel() {
        let src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nvn 0 0 1\nf 1/1/1 2/1/1 3/-1/1\nf 1//1 2//1 3//1\nf 1 2 3\n";
        let (text, counts) = validate_obj(src, &f()).expect("valid");
        assert!(text.starts_with("vt 0 1\n"), "{text}");
        assert!(
            text.contains("f 1/2/1 2/2/1 3/-1/1"),
            "positive vt shift, negative kept: {text}"
        );
        assert!(text.contains("f 1/1/1 2/1/1 3/1/1"), "{text}");
        assert!(text.contains("f 1/1 2/1 3/1"), "{text}");
        assert_eq!(counts.faces_without_uvs, 2);
        let (text, counts) =
            validate_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &f()).expect("valid");
        assert!(!text.contains("vt"), "no UVs anywhere: no sentinel");
        assert_eq!(counts.faces_without_uvs, 1);
    }

    #[test]
    fn mtl_colours_are_checked_and_expanded() {
        let err = validate_mtl("newmtl a\nKd 0.5 0.5\n", &f())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("t.obj:2: Kd needs 3 numbers, found 2"),
            "{err}"
        );
        let err = validate_mtl("newmtl a\nNs abc\n", &f())
            .unwrap_err()
            .to_string();
        assert!(err.contains("t.obj:2: Ns: `abc` is not a number"), "{err}");
        let text = validate_mtl("newmtl a\n  Kd 0.25 # grey\nKa 0.1 0.2 0.3 # Red\n", &f())
            .expect("valid");
        assert!(text.contains("Kd 0.25 0.25 0.25"), "{text}");
        assert!(text.contains("Ka 0.1 0.2 0.3"), "{text}");
    }

    /// A one-triangle OBJ whose material names `texture` as its map_Kd, in `dir`.
    fn textured(dir: &Path, texture: &str) -> PathBuf {
        std::fs::write(dir.join("t.mtl"), format!("newmtl m\nmap_Kd {texture}\n")).expect("mtl");
        let obj = dir.join("t.obj");
        std::fs::write(
            &obj,
            "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n",
        )
        .expect("obj");
        obj
    }

    fn load_err(obj: &Path) -> String {
        match load_obj(obj, &ObjOptions::default()) {
            Ok(_) => panic!("{} loaded", obj.display()),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn texture_errors_name_the_texture_once() {
        let d = tempfile::tempdir().expect("tempdir");
        std::fs::write(d.path().join("bad.png"), b"\x89PNG\r\n\x1a\nnot a png").expect("png");
        let err = load_err(&textured(d.path(), "bad.png"));
        assert_eq!(err.matches("bad.png").count(), 1, "{err}");
        assert!(err.contains("cannot decode texture"), "{err}");
        assert!(err.contains("material `m` in"), "{err}");
        let err = load_err(&textured(d.path(), "absent.png"));
        assert_eq!(err.matches("absent.png").count(), 1, "{err}");
        assert!(err.contains("cannot read texture"), "{err}");
    }

    #[test]
    fn a_directory_as_texture_is_reported_as_one() {
        let d = tempfile::tempdir().expect("tempdir");
        for name in ["maps", "maps.png"] {
            std::fs::create_dir(d.path().join(name)).expect("dir");
            let err = load_err(&textured(d.path(), name));
            assert!(err.contains("is a directory"), "{err}");
            assert!(!err.contains("format could not be determined"), "{err}");
            assert!(Texture::load(&d.path().join(name), true).is_err());
        }
    }

    #[test]
    fn loads_from_memory_without_touching_the_disk() {
        let mut files = crate::files::MemoryFiles::new();
        files.insert(
            "m/t.obj",
            "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        );
        files.insert("m/t.mtl", "newmtl a\nKd 0.25\n");
        let data = load_obj_from(&files, Path::new("m/t.obj"), &ObjOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(data.objects.len(), 1);
        assert_eq!(data.materials[0].kd, [0.25; 3]);
        let err = load_obj_from(&files, Path::new("m/none.obj"), &ObjOptions::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(err.starts_with("m/none.obj: cannot read"), "{err}");
    }

    #[test]
    fn texture_refs_normalise_backslashes_and_options() {
        assert_eq!(
            texture_ref(".\\wal67ar_small.jpg"),
            ("./wal67ar_small.jpg".into(), None)
        );
        assert_eq!(
            texture_ref("-bm 0.5 maps/h.png"),
            ("maps/h.png".into(), Some(0.5))
        );
    }
}
