//! Passes declared once. A compute pass is one [`ComputeDecl`]: its shader and defines, its
//! bindings by name and kind (with how the shader uses each: read, write or both), its
//! push-constant struct ([`push_constants!`]), its shader-side constants (flag bits) and its
//! group size. From that one value come
//! - the descriptor set layout and the pipeline ([`ComputeDecl::build`]: no image, no memory, no
//!   command buffer: the compile-only build);
//! - every shader-side number: `BINDING_<NAME>` (binding numbers are the bindings' positions:
//!   none is written by hand), `PUSH_CONSTANTS` (the GLSL block of the Rust struct, checked for
//!   matching offsets when the struct is declared), `LOCAL_SIZE_X/Y` and the declared constants;
//! - at record time, from one [`Binds`] list naming what each binding holds this frame: the
//!   descriptor writes (by name, kind checked: a missing or unknown name or a wrong kind is an
//!   error, never a panic) and the barriers (derived from the binding's declared use).
//!
//! Resources a technique owns are declared as [`ResourceDecl`]s ([`Resources`]): the memory
//! estimate and the allocation come from the same list, and a binding whose name matches a
//! resource binds it without being named again. A resource declared [`ResourceDecl::history`]
//! is a ping-pong pair ([`History`]): one type for every temporal pass.
//!
//! Descriptor sets are made per dispatch from the binds (kept by the command buffer until its
//! submission completes), so a pass has no per-parity or per-input set to keep in step with its
//! resources.

use std::collections::BTreeMap;

use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, GpuError,
    Image, ImageDesc, PassKind, Pipeline, Profiler, Readback, Result, Sampler, SamplerDesc,
    SetLayout, Shaders, Traffic, Write, vk,
};

use crate::memory::MemoryEstimate;

mod graphics;
pub use graphics::{GraphicsDecl, GraphicsPass, RasterState};

/// How a shader uses a storage binding (the barrier before the dispatch follows from it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Use {
    Read,
    Write,
    ReadWrite,
}

/// The sampler a sampled binding reads through (made once per pass).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    /// Bilinear, clamp to edge, normalised coordinates: TAA's history reads.
    Linear,
    /// Bilinear in texel units (Vulkan's unnormalizedCoordinates): the resolve's history reads.
    LinearTexels,
    /// The sampler comes with the image ([`Binds::sampled`]): the scene's textures, mipmapped and
    /// trilinear, sampled through the scene's own sampler.
    Given,
}

impl Filter {
    /// The sampler the pass makes for this filter (`None`: the sampler comes with the image).
    fn desc(self) -> Option<SamplerDesc> {
        match self {
            Filter::Nearest => Some(SamplerDesc::NEAREST),
            Filter::Linear => Some(SamplerDesc {
                linear: true,
                ..SamplerDesc::NEAREST
            }),
            Filter::LinearTexels => Some(SamplerDesc {
                linear: true,
                unnormalized: true,
                ..SamplerDesc::NEAREST
            }),
            Filter::Given => None,
        }
    }
}

/// What one binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindKind {
    /// A combined image sampler read through `Filter`.
    Sampled(Filter),
    StorageImage(Use),
    StorageBuffer(Use),
    Uniform,
}

impl BindKind {
    fn descriptor(self) -> (DescriptorKind, u32) {
        match self {
            BindKind::Sampled(_) => (DescriptorKind::CombinedImageSampler, 1),
            BindKind::StorageImage(_) => (DescriptorKind::StorageImage, 1),
            BindKind::StorageBuffer(_) => (DescriptorKind::StorageBuffer, 1),
            BindKind::Uniform => (DescriptorKind::UniformBuffer, 1),
        }
    }

    fn what(self) -> &'static str {
        match self {
            BindKind::Sampled(_) => "sampled image",
            BindKind::StorageImage(_) => "storage image",
            BindKind::StorageBuffer(_) | BindKind::Uniform => "buffer",
        }
    }

    /// The access a compute dispatch makes.
    fn compute_access(self) -> Access {
        match self {
            BindKind::Sampled(_) => Access::ComputeSampled,
            BindKind::StorageImage(u) | BindKind::StorageBuffer(u) => match u {
                Use::Read => Access::ComputeStorageRead,
                Use::Write => Access::ComputeStorageWrite,
                Use::ReadWrite => Access::ComputeStorageReadWrite,
            },
            BindKind::Uniform => Access::ComputeUniformRead,
        }
    }

    /// The access a draw makes (storage images are not declared for graphics passes: refused
    /// when the pass is built).
    fn graphics_access(self) -> Access {
        match self {
            BindKind::Sampled(_) => Access::FragmentSampled,
            BindKind::StorageBuffer(Use::Read) | BindKind::Uniform => Access::GraphicsRead,
            BindKind::StorageBuffer(_) | BindKind::StorageImage(_) => Access::FragmentStorageWrite,
        }
    }
}

/// A descriptor set several passes share and that is made once, not per dispatch: the scene's
/// buffers, one material's textures. Its bindings are declared once like a pass's own (numbered
/// by position, `BINDING_<NAME>`), and a pass that uses it says at which set index
/// ([`SetRef::Shared`]; the shader reads the index as `SET_<NAME>`). Its resources are
/// barriered by their owner (the scene's buffers are written by the host before the frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SetDecl {
    pub name: &'static str,
    pub bindings: &'static [Binding],
}

impl SetDecl {
    pub fn binding_descs(&self) -> Vec<BindingDesc> {
        binding_descs(self.bindings)
    }

    /// One set of this declaration, its bindings from `binds` (checked by name and kind; a
    /// sampled binding must come with its sampler: [`Filter::Given`]).
    pub fn make(
        &self,
        gpu: &Gpu,
        owner: &str,
        layout: &SetLayout,
        binds: &Binds,
    ) -> Result<DescriptorSet> {
        let name = format!("{owner}.{}", self.name);
        check_binds(&name, self.bindings, binds)?;
        make_set(gpu, &name, layout, self.bindings, binds, &BTreeMap::new())
    }
}

/// One set of a pass's pipeline layout: the pass's own bindings (bound from [`Binds`] at each
/// dispatch or draw pass; `SET_PASS` in the shader) or a shared set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetRef {
    Own,
    Shared(SetDecl),
}

/// The set layout's bindings of `bindings`: numbered by position.
fn binding_descs(bindings: &[Binding]) -> Vec<BindingDesc> {
    bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let (kind, count) = b.kind.descriptor();
            BindingDesc {
                name: b.name,
                binding: i as u32,
                kind,
                count,
            }
        })
        .collect()
}

/// The bindings of set `r` (the pass's own: `own`).
fn set_bindings<'a>(r: &SetRef, own: &'a [Binding]) -> &'a [Binding] {
    match r {
        SetRef::Own => own,
        SetRef::Shared(s) => s.bindings,
    }
}

/// `SET_<NAME>` (`SET_PASS` for the own set) and `BINDING_<NAME>` of every set.
fn set_defines(sets: &[SetRef], own: &[Binding]) -> Vec<(String, String)> {
    let mut d = Vec::new();
    for (i, r) in sets.iter().enumerate() {
        let name = match r {
            SetRef::Own => "PASS".to_string(),
            SetRef::Shared(s) => s.name.to_uppercase(),
        };
        d.push((format!("SET_{name}"), i.to_string()));
        d.extend(
            binding_descs(set_bindings(r, own))
                .iter()
                .map(BindingDesc::define),
        );
    }
    d
}

/// A declaration's own checks: binding names unique across its sets (they share the shader's
/// `BINDING_<NAME>` namespace), the own set listed at most once.
fn check_sets(pass: &str, sets: &[SetRef], own: &[Binding]) -> Result<()> {
    if sets.iter().filter(|r| **r == SetRef::Own).count() > 1 {
        return Err(declaration(pass, "its own set twice".into()));
    }
    let all: Vec<&Binding> = sets.iter().flat_map(|r| set_bindings(r, own)).collect();
    for (i, b) in all.iter().enumerate() {
        if all[..i].iter().any(|o| o.name == b.name) {
            return Err(declaration(pass, format!("binding `{}` twice", b.name)));
        }
    }
    if !own.is_empty() && !sets.contains(&SetRef::Own) {
        return Err(declaration(
            pass,
            "bindings of its own but no set for them".into(),
        ));
    }
    Ok(())
}

/// The set layouts of `sets`, in set order.
fn set_layouts(gpu: &Gpu, pass: &str, sets: &[SetRef], own: &[Binding]) -> Result<Vec<SetLayout>> {
    sets.iter()
        .map(|r| {
            let name = match r {
                SetRef::Own => format!("{pass}.set_layout"),
                SetRef::Shared(s) => format!("{pass}.{}_layout", s.name),
            };
            SetLayout::new(gpu, &name, &binding_descs(set_bindings(r, own)))
        })
        .collect()
}

/// One sampler per filter the sampled bindings name (given samplers come with their images).
fn samplers(gpu: &Gpu, pass: &str, bindings: &[Binding]) -> Result<BTreeMap<u8, Sampler>> {
    let mut samplers = BTreeMap::new();
    for b in bindings {
        if let BindKind::Sampled(filter) = b.kind
            && let Some(desc) = filter.desc()
            && !samplers.contains_key(&(filter as u8))
        {
            let s = Sampler::new(gpu, &format!("{pass}.{filter:?}").to_lowercase(), desc)?;
            samplers.insert(filter as u8, s);
        }
    }
    Ok(samplers)
}

/// Checks that `binds` give every one of `bindings` something of its kind, and name nothing
/// `bindings` lack (resources taken by [`Binds::of`] that are not bound here are other passes'
/// and are ignored).
fn check_binds(pass: &str, bindings: &[Binding], binds: &Binds) -> Result<()> {
    for (name, _, explicit) in &binds.list {
        if *explicit && !bindings.iter().any(|b| b.name == *name) {
            return Err(declaration(
                pass,
                format!("`{name}` is bound but not declared"),
            ));
        }
    }
    for b in bindings {
        let given = binds
            .get(b.name)
            .ok_or_else(|| declaration(pass, format!("nothing bound to `{}`", b.name)))?;
        let ok = matches!(
            (b.kind, given),
            (BindKind::Sampled(Filter::Given), Bound::Sampled(..))
                | (BindKind::StorageImage(_), Bound::Image(_))
                | (
                    BindKind::StorageBuffer(_) | BindKind::Uniform,
                    Bound::Buffer(_) | Bound::Part(..)
                )
        ) || matches!(
            (b.kind, given),
            (BindKind::Sampled(f), Bound::Image(_)) if f != Filter::Given
        );
        if !ok {
            let got = match given {
                Bound::Image(_) => "an image",
                Bound::Sampled(..) => "an image with its sampler",
                Bound::Buffer(_) | Bound::Part(..) => "a buffer",
                Bound::Set(_) => "a set",
            };
            let what = match b.kind {
                BindKind::Sampled(Filter::Given) => "sampled image with a given sampler",
                k => k.what(),
            };
            return Err(declaration(
                pass,
                format!("`{}` is a {what}, given {got}", b.name),
            ));
        }
    }
    Ok(())
}

/// The descriptor set of `bindings` from `binds` (checked by [`check_binds`]; anything else is
/// still an error here or in `DescriptorSet::update`).
fn make_set(
    gpu: &Gpu,
    name: &str,
    layout: &SetLayout,
    bindings: &[Binding],
    binds: &Binds,
    samplers: &BTreeMap<u8, Sampler>,
) -> Result<DescriptorSet> {
    let mut writes = Vec::with_capacity(bindings.len());
    for (i, b) in bindings.iter().enumerate() {
        let n = i as u32;
        let sampler = match b.kind {
            BindKind::Sampled(filter) => samplers.get(&(filter as u8)),
            _ => None,
        };
        match (binds.get(b.name), sampler) {
            (Some(Bound::Sampled(img, s)), _) => writes.push(Write::Sampled(n, vec![(*img, *s)])),
            (Some(Bound::Image(img)), Some(s)) => {
                writes.push(Write::Sampled(n, vec![(*img, s)]));
            }
            (Some(Bound::Image(img)), None) => writes.push(Write::Storage(n, img)),
            (Some(Bound::Buffer(x)), _) => writes.push(Write::Buffer(n, x)),
            (Some(Bound::Part(x, offset, bytes)), _) => {
                writes.push(Write::BufferRange(n, x, *offset, *bytes));
            }
            _ => {
                return Err(declaration(
                    name,
                    format!("`{}` cannot be bound as given", b.name),
                ));
            }
        }
    }
    DescriptorSet::new(gpu, &format!("{name}.set"), layout, &writes)
}

/// One binding of a pass: its name (the shader's `BINDING_<NAME>`) and what it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub name: &'static str,
    pub kind: BindKind,
}

impl Binding {
    pub const fn sampled(name: &'static str) -> Binding {
        Binding::sampled_with(name, Filter::Nearest)
    }
    pub const fn sampled_with(name: &'static str, filter: Filter) -> Binding {
        Binding {
            name,
            kind: BindKind::Sampled(filter),
        }
    }
    pub const fn image(name: &'static str, u: Use) -> Binding {
        Binding {
            name,
            kind: BindKind::StorageImage(u),
        }
    }
    pub const fn buffer(name: &'static str, u: Use) -> Binding {
        Binding {
            name,
            kind: BindKind::StorageBuffer(u),
        }
    }
    pub const fn uniform(name: &'static str) -> Binding {
        Binding {
            name,
            kind: BindKind::Uniform,
        }
    }
}

/// A GLSL type a push-constant member may have: its name and its std430 alignment.
pub trait GlslType {
    const NAME: &'static str;
    const ALIGN: usize;
}

macro_rules! glsl_types {
    ($($t:ty => $name:literal, $align:literal;)*) => {
        $(impl GlslType for $t {
            const NAME: &'static str = $name;
            const ALIGN: usize = $align;
        })*
    };
}

glsl_types! {
    f32 => "float", 4;
    u32 => "uint", 4;
    i32 => "int", 4;
    [f32; 2] => "vec2", 8;
    [u32; 2] => "uvec2", 8;
    [i32; 2] => "ivec2", 8;
    [f32; 4] => "vec4", 16;
    [u32; 4] => "uvec4", 16;
    [i32; 4] => "ivec4", 16;
    [[f32; 4]; 4] => "mat4", 16;
}

/// An array member of a push-constant block (`name: [f32; N] as array`): std430 arrays of
/// scalars have the scalar's stride and alignment, as `repr(C)` arrays do.
pub trait GlslArray {
    const ELEM: &'static str;
    const LEN: usize;
    const ALIGN: usize;
}

impl<T: GlslType, const N: usize> GlslArray for [T; N] {
    const ELEM: &'static str = T::NAME;
    const LEN: usize = N;
    const ALIGN: usize = T::ALIGN;
}

/// One member of a push-constant block.
#[derive(Clone, Copy, Debug)]
pub struct PushField {
    pub glsl_type: &'static str,
    pub name: &'static str,
    /// Array length (0: not an array).
    pub len: usize,
    /// Byte offset in the Rust struct (the GLSL block's, std430, when the layout is right:
    /// tests compare them with the SPIR-V's Offset decorations).
    pub offset: usize,
}

/// A push-constant struct declared with [`push_constants!`]: its bytes and its GLSL block.
pub trait PushConstants: bytemuck::Pod {
    const FIELDS: &'static [PushField];

    /// `layout(push_constant) uniform Push { ... } pc;`, the `PUSH_CONSTANTS` define.
    fn glsl() -> String {
        let members: String = Self::FIELDS
            .iter()
            .map(|f| match f.len {
                0 => format!(" {} {};", f.glsl_type, f.name),
                n => format!(" {} {}[{n}];", f.glsl_type, f.name),
            })
            .collect();
        format!("layout(push_constant) uniform Push {{{members} }} pc;")
    }
}

/// Declares a `#[repr(C)]` push-constant struct and its GLSL block in one place. Member types
/// are Rust types with a GLSL name (`[f32; 4]` = vec4, `u32` = uint, ...); an array of scalars
/// is `name: [f32; N] as array`. A member whose offset would differ between `repr(C)` and
/// GLSL's std430 is a compile error.
#[macro_export]
macro_rules! push_constants {
    ($(#[$m:meta])* $vis:vis struct $name:ident {
        $($(#[$fm:meta])* $f:ident : $t:ty $(as $array:ident)?),* $(,)?
    }) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name { $($(#[$fm])* pub $f: $t),* }

        impl $crate::pass::PushConstants for $name {
            const FIELDS: &'static [$crate::pass::PushField] = &[$(
                $crate::push_constants!(@field $name, $f : $t $(as $array)?)
            ),*];
        }

        const _: () = {
            $(assert!(
                ::std::mem::offset_of!($name, $f)
                    % $crate::push_constants!(@align $t $(as $array)?) == 0,
                "a push-constant member is not at its std430 offset: reorder the struct"
            );)*
        };
    };
    (@field $name:ident, $f:ident : $t:ty) => {
        $crate::pass::PushField {
            glsl_type: <$t as $crate::pass::GlslType>::NAME,
            name: stringify!($f),
            len: 0,
            offset: ::std::mem::offset_of!($name, $f),
        }
    };
    (@field $name:ident, $f:ident : $t:ty as array) => {
        $crate::pass::PushField {
            glsl_type: <$t as $crate::pass::GlslArray>::ELEM,
            name: stringify!($f),
            len: <$t as $crate::pass::GlslArray>::LEN,
            offset: ::std::mem::offset_of!($name, $f),
        }
    };
    (@align $t:ty) => { <$t as $crate::pass::GlslType>::ALIGN };
    (@align $t:ty as array) => { <$t as $crate::pass::GlslArray>::ALIGN };
}

push_constants! {
    /// The push constants of a pass that declares none (its dispatches pass `&NoPush`).
    pub struct NoPush {}
}

/// One compute pass, declared once.
#[derive(Clone, Debug)]
pub struct ComputeDecl {
    /// The pipeline's name (debug utils) and the profiler scope of [`ComputePass::dispatch`].
    pub name: String,
    /// Path under `shaders/`.
    pub shader: &'static str,
    pub defines: Vec<(String, String)>,
    /// The pass's own set: bound from [`Binds`] at each dispatch.
    pub bindings: Vec<Binding>,
    /// The pipeline layout's sets: the own set first, then the shared ones
    /// ([`ComputeDecl::shared`]).
    pub sets: Vec<SetRef>,
    /// The push-constant block's bytes and GLSL (`PUSH_CONSTANTS`), and its members.
    pub push: Option<(u32, String)>,
    pub push_fields: &'static [PushField],
    /// Local size x, y (`LOCAL_SIZE_X`, `LOCAL_SIZE_Y`).
    pub group: [u32; 2],
}

impl ComputeDecl {
    pub fn new(name: impl Into<String>, shader: &'static str) -> ComputeDecl {
        ComputeDecl {
            name: name.into(),
            shader,
            defines: Vec::new(),
            bindings: Vec::new(),
            sets: vec![SetRef::Own],
            push: None,
            push_fields: &[],
            group: [8, 8],
        }
    }

    /// A shared set at the next set index (bound with [`Binds::set`]).
    pub fn shared(mut self, set: SetDecl) -> ComputeDecl {
        self.sets.push(SetRef::Shared(set));
        self
    }

    pub fn define(mut self, name: &str, value: impl ToString) -> ComputeDecl {
        self.defines.push((name.to_string(), value.to_string()));
        self
    }

    /// Shader-side constants (flag bits, limits) from their Rust values, as `uint` literals
    /// (`4u`): for expressions; values the preprocessor compares are plain [`ComputeDecl::define`]s.
    pub fn constants(mut self, c: &[(&str, u32)]) -> ComputeDecl {
        for (name, v) in c {
            self.defines.push((name.to_string(), format!("{v}u")));
        }
        self
    }

    pub fn bind(mut self, b: Binding) -> ComputeDecl {
        self.bindings.push(b);
        self
    }

    pub fn bindings(mut self, b: &[Binding]) -> ComputeDecl {
        self.bindings.extend_from_slice(b);
        self
    }

    pub fn push<P: PushConstants>(mut self) -> ComputeDecl {
        self.push = Some((std::mem::size_of::<P>() as u32, P::glsl()));
        self.push_fields = P::FIELDS;
        self
    }

    pub fn group(mut self, x: u32, y: u32) -> ComputeDecl {
        self.group = [x, y];
        self
    }

    /// The own set layout's bindings: numbered by position.
    pub fn binding_descs(&self) -> Vec<BindingDesc> {
        binding_descs(&self.bindings)
    }

    /// Every define the shader is compiled with.
    pub fn all_defines(&self) -> Vec<(String, String)> {
        let mut d = self.defines.clone();
        d.extend(set_defines(&self.sets, &self.bindings));
        if let Some((_, glsl)) = &self.push {
            d.push(("PUSH_CONSTANTS".into(), glsl.clone()));
        }
        d.push(("LOCAL_SIZE_X".into(), self.group[0].to_string()));
        d.push(("LOCAL_SIZE_Y".into(), self.group[1].to_string()));
        d
    }

    /// Checks the declaration itself: unique binding names, the own set first.
    fn check(&self) -> Result<()> {
        if self.sets.first() != Some(&SetRef::Own) {
            return Err(declaration(&self.name, "its own set is not set 0".into()));
        }
        check_sets(&self.name, &self.sets, &self.bindings)
    }

    /// The compile-only build: set layouts, samplers and pipeline; no image, no memory.
    pub fn build(&self, gpu: &Gpu, shaders: &Shaders) -> Result<ComputePass> {
        self.check()?;
        let layouts = set_layouts(gpu, &self.name, &self.sets, &self.bindings)?;
        let cs = shaders.compile(self.shader, &self.all_defines())?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: &self.name,
                shader: &cs,
                set_layouts: &layouts.iter().collect::<Vec<_>>(),
                push_constant_bytes: self.push.as_ref().map_or(0, |p| p.0),
            },
        )?;
        let samplers = samplers(gpu, &self.name, &self.bindings)?;
        Ok(ComputePass {
            decl: self.clone(),
            layouts,
            pipeline,
            samplers,
            referenced: Referenced::of(&self.name, &[cs.as_slice()], 0),
        })
    }
}

fn declaration(pass: &str, message: String) -> GpuError {
    GpuError::Declaration {
        pass: pass.to_string(),
        message,
    }
}

/// What one binding holds this frame.
#[derive(Clone)]
pub enum Bound<'a> {
    Image(&'a Image),
    /// A sampled image with its own sampler ([`Filter::Given`]).
    Sampled(&'a Image, &'a Sampler),
    Buffer(&'a Buffer),
    /// `bytes` of a buffer from `offset`: one buffer seen as two bindings (the lights' first
    /// part as a uniform buffer, the rest as a storage buffer: [`crate::gpu_types::SplitBuffer`]).
    Part(&'a Buffer, u64, u64),
    /// A shared set, by its [`SetDecl::name`].
    Set(&'a DescriptorSet),
}

/// The resources of one dispatch, by binding name: what [`Resources`] hold of the same names,
/// plus what is named here (the technique's targets, a post pass's input).
#[derive(Clone, Default)]
pub struct Binds<'a> {
    /// Name, what it holds, and whether it was named here (not taken from [`Resources`]): a
    /// name given here that the pass does not declare is an error (a misspelt binding).
    list: Vec<(&'static str, Bound<'a>, bool)>,
}

impl<'a> Binds<'a> {
    pub fn new() -> Binds<'a> {
        Binds::default()
    }

    /// Every resource of `res` under its own name (histories: see [`Binds::history`]).
    pub fn of(res: &'a Resources) -> Binds<'a> {
        let mut b = Binds::new();
        for (name, r) in &res.items {
            match r {
                Owned::Image(i) => b.list.push((name, Bound::Image(i), false)),
                Owned::Buffer(x) => b.list.push((name, Bound::Buffer(x), false)),
                Owned::History(_) | Owned::Readback(_) => {}
            }
        }
        b
    }

    /// Binds `name` (a sampled or storage image binding).
    pub fn image(mut self, name: &'static str, image: &'a Image) -> Binds<'a> {
        self.set(name, Bound::Image(image));
        self
    }

    pub fn buffer(mut self, name: &'static str, buffer: &'a Buffer) -> Binds<'a> {
        self.set(name, Bound::Buffer(buffer));
        self
    }

    /// Binds `name` to `bytes` of `buffer` from `offset`.
    pub fn buffer_part(
        mut self,
        name: &'static str,
        buffer: &'a Buffer,
        offset: u64,
        bytes: u64,
    ) -> Binds<'a> {
        self.set(name, Bound::Part(buffer, offset, bytes));
        self
    }

    /// Binds `name` (a sampled binding of [`Filter::Given`]) to `image` read through `sampler`.
    pub fn sampled(
        mut self,
        name: &'static str,
        image: &'a Image,
        sampler: &'a Sampler,
    ) -> Binds<'a> {
        self.set(name, Bound::Sampled(image, sampler));
        self
    }

    /// Binds the shared set `set` (made by [`SetDecl::make`]) under its declaration's name.
    pub fn shared(mut self, decl: &SetDecl, set: &'a DescriptorSet) -> Binds<'a> {
        self.set(decl.name, Bound::Set(set));
        self
    }

    /// A history's slots for `frame`: the one read (written last frame) at `read`, the one
    /// written this frame at `write`.
    pub fn history(
        self,
        h: &'a History<Image>,
        frame: u32,
        read: &'static str,
        write: &'static str,
    ) -> Binds<'a> {
        self.image(read, h.read(frame)).image(write, h.write(frame))
    }

    /// The entries `pass` declares: one list of a frame's resources serves several passes,
    /// each binding (and barriering) its own.
    pub fn only(&self, pass: &ComputePass) -> Binds<'a> {
        Binds {
            list: self
                .list
                .iter()
                .filter(|(n, ..)| {
                    pass.decl.bindings.iter().any(|b| b.name == *n)
                        || pass.decl.sets.iter().any(|r| shared_named(r, n))
                })
                .cloned()
                .collect(),
        }
    }

    /// The entries named in `bindings`.
    fn own_only(&self, bindings: &[Binding]) -> Binds<'a> {
        Binds {
            list: self
                .list
                .iter()
                .filter(|(n, ..)| bindings.iter().any(|b| b.name == *n))
                .cloned()
                .collect(),
        }
    }

    /// The names given here (not taken from [`Resources`]).
    fn explicit(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.list.iter().filter(|e| e.2).map(|e| e.0)
    }

    /// The entries that are not shared sets (what a pass's own set is checked against).
    fn without_sets(&self) -> Binds<'a> {
        Binds {
            list: self
                .list
                .iter()
                .filter(|(_, b, _)| !matches!(b, Bound::Set(_)))
                .cloned()
                .collect(),
        }
    }

    /// The shared set `decl` bound under its name.
    fn shared_set(&self, pass: &str, decl: &SetDecl) -> Result<&'a DescriptorSet> {
        match self.get(decl.name) {
            Some(Bound::Set(s)) => Ok(*s),
            _ => Err(declaration(
                pass,
                format!("no `{}` set bound (Binds::shared)", decl.name),
            )),
        }
    }

    fn set(&mut self, name: &'static str, b: Bound<'a>) {
        match self.list.iter_mut().find(|(n, ..)| *n == name) {
            Some(e) => (e.1, e.2) = (b, true),
            None => self.list.push((name, b, true)),
        }
    }

    fn get(&self, name: &str) -> Option<&Bound<'a>> {
        self.list
            .iter()
            .find(|(n, ..)| *n == name)
            .map(|(_, b, _)| b)
    }
}

/// A built compute pass: pipeline, set layout and the samplers its sampled bindings read
/// through.
pub struct ComputePass {
    pub decl: ComputeDecl,
    layouts: Vec<SetLayout>,
    pipeline: Pipeline,
    samplers: BTreeMap<u8, Sampler>,
    referenced: Referenced,
}

impl ComputePass {
    pub fn name(&self) -> &str {
        &self.decl.name
    }

    /// Checks that `binds` give every binding of the declaration something of its kind, name
    /// nothing the declaration lacks (resources taken by [`Binds::of`] that this pass does not
    /// bind are other passes' and are ignored), and give every shared set.
    pub fn check(&self, binds: &Binds) -> Result<()> {
        check_binds(&self.decl.name, &self.decl.bindings, &binds.without_sets())?;
        for r in &self.decl.sets {
            if let SetRef::Shared(s) = r {
                binds.shared_set(&self.decl.name, s)?;
            }
        }
        for (name, b, _) in &binds.list {
            if matches!(b, Bound::Set(_)) && !self.decl.sets.iter().any(|r| shared_named(r, name)) {
                return Err(declaration(
                    &self.decl.name,
                    format!("set `{name}` is bound but not declared"),
                ));
            }
        }
        Ok(())
    }

    /// Records the barriers for `binds`, then (timed under the pass's name) one dispatch of
    /// `groups` work groups with `push`.
    pub fn dispatch<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        binds: &Binds,
        push: &P,
        groups: [u32; 3],
    ) -> Result<()> {
        self.prepare(cmd, binds)?;
        let scope = profiler.begin(cmd, &self.decl.name, PassKind::Compute);
        let r = self.dispatch_untimed(cmd, binds, push, groups);
        profiler.end(cmd, scope);
        r
    }

    /// [`ComputePass::dispatch`] over the pixels of a `width` x `height` image.
    pub fn dispatch_2d<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        binds: &Binds,
        push: &P,
        size: (u32, u32),
    ) -> Result<()> {
        self.dispatch(cmd, profiler, binds, push, self.groups_2d(size))
    }

    /// The work groups covering a `width` x `height` image, one invocation per pixel.
    pub fn groups_2d(&self, (width, height): (u32, u32)) -> [u32; 3] {
        let g = self.decl.group;
        [width.div_ceil(g[0]), height.div_ceil(g[1]), 1]
    }

    /// The barriers `binds` need before a dispatch (for passes that time several dispatches
    /// as one scope).
    pub fn prepare(&self, cmd: &mut Cmd, binds: &Binds) -> Result<()> {
        self.check(binds)?;
        record_uses(
            cmd,
            &self.decl.bindings,
            binds,
            BindKind::compute_access,
            &self.referenced,
        );
        Ok(())
    }

    /// One dispatch without barriers or timing (after [`ComputePass::prepare`]).
    pub fn dispatch_untimed<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        binds: &Binds,
        push: &P,
        groups: [u32; 3],
    ) -> Result<()> {
        let g = self.decl.group;
        cmd.add_traffic(&Traffic {
            compute_invocations: groups.iter().map(|&n| u64::from(n)).product::<u64>()
                * u64::from(g[0] * g[1]),
            dispatches: 1,
            ..Traffic::default()
        });
        self.record(cmd, binds, push, |cmd| {
            cmd.dispatch(groups[0], groups[1], groups[2]);
        })
    }

    /// The barriers of [`ComputePass::prepare`] and those of `args` read as an indirect
    /// dispatch's parameters (first: [`Access::ComputeIndirect`] also covers the shader's reads
    /// of `args` where the pass binds it, so that their barrier, read after read, is none).
    pub fn prepare_indirect(&self, cmd: &mut Cmd, binds: &Binds, args: &Buffer) -> Result<()> {
        cmd.use_buffer(args, Access::ComputeIndirect);
        self.prepare(cmd, binds)
    }

    /// Records the barriers (with `args`'), then (timed under the pass's name) one dispatch whose
    /// group counts the GPU wrote into `args` at byte `offset` (VkDispatchIndirectCommand).
    pub fn dispatch_indirect<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        binds: &Binds,
        push: &P,
        (args, offset): (&Buffer, u64),
    ) -> Result<()> {
        self.prepare_indirect(cmd, binds, args)?;
        let scope = profiler.begin(cmd, &self.decl.name, PassKind::Compute);
        let r = self.dispatch_indirect_untimed(cmd, binds, push, (args, offset));
        profiler.end(cmd, scope);
        r
    }

    /// One indirect dispatch without barriers or timing (after
    /// [`ComputePass::prepare_indirect`]).
    pub fn dispatch_indirect_untimed<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        binds: &Binds,
        push: &P,
        (args, offset): (&Buffer, u64),
    ) -> Result<()> {
        cmd.add_traffic(&Traffic {
            indirect_dispatches: 1,
            ..Traffic::default()
        });
        self.record(cmd, binds, push, |cmd| cmd.dispatch_indirect(args, offset))
    }

    /// Binds the pipeline, the dispatch's set and `push`, then records `dispatch`.
    fn record<P: PushConstants>(
        &self,
        cmd: &mut Cmd,
        binds: &Binds,
        push: &P,
        dispatch: impl FnOnce(&mut Cmd),
    ) -> Result<()> {
        let want = self.decl.push.as_ref().map_or(0, |p| p.0) as usize;
        if std::mem::size_of::<P>() != want {
            return Err(declaration(
                &self.decl.name,
                format!(
                    "push constants of {} bytes, declared {want}",
                    std::mem::size_of::<P>()
                ),
            ));
        }
        let set = make_set(
            cmd.gpu(),
            &self.decl.name,
            &self.layouts[0],
            &self.decl.bindings,
            &binds.without_sets(),
            &self.samplers,
        )?;
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &set);
        for (i, r) in self.decl.sets.iter().enumerate() {
            if let SetRef::Shared(s) = r {
                cmd.bind_set(
                    &self.pipeline,
                    i as u32,
                    binds.shared_set(&self.decl.name, s)?,
                );
            }
        }
        if want > 0 {
            cmd.push_constants(&self.pipeline, bytemuck::bytes_of(push));
        }
        dispatch(cmd);
        cmd.keep(set);
        Ok(())
    }
}

/// Which bindings of a pass's own set its compiled shaders reference
/// (cbr_gpu::referenced_bindings): only those count in its traffic. A binding the shaders do
/// not reference in this variant (a debug output, another mode's history) moves nothing.
#[derive(Clone, Debug, Default)]
pub struct Referenced {
    /// The pass's name (the `cbr::traffic` debug log names each binding's bytes under it).
    pass: String,
    bindings: Option<std::collections::BTreeSet<u32>>,
}

impl Referenced {
    /// From the shaders' SPIR-V, for the own set at index `set`; unknown (every binding
    /// counts) where a module does not say.
    pub fn of(pass: &str, modules: &[&[u32]], set: u32) -> Referenced {
        let mut all = std::collections::BTreeSet::new();
        for m in modules {
            match cbr_gpu::referenced_bindings(m) {
                Some(r) => all.extend(r.into_iter().filter(|p| p.0 == set).map(|p| p.1)),
                None => {
                    return Referenced {
                        pass: pass.into(),
                        bindings: None,
                    };
                }
            }
        }
        Referenced {
            pass: pass.into(),
            bindings: Some(all),
        }
    }

    pub fn has(&self, binding: usize) -> bool {
        self.bindings
            .as_ref()
            .is_none_or(|r| u32::try_from(binding).is_ok_and(|b| r.contains(&b)))
    }
}

/// Records, for each of `bindings`, the barrier its declared use (`access`: a compute dispatch's
/// or a draw's) needs on what `binds` give it.
///
/// It also declares what the bindings move to the profiler's traffic count ([`Traffic`]): each
/// bound image or buffer once in full, read, written or both as its binding says.
fn record_uses(
    cmd: &mut Cmd,
    bindings: &[Binding],
    binds: &Binds,
    access: fn(BindKind) -> Access,
    referenced: &Referenced,
) {
    let mut t = Traffic::default();
    for (i, b) in bindings.iter().enumerate() {
        let access = access(b.kind);
        let (bytes, host) = match binds.get(b.name) {
            Some(Bound::Image(i) | Bound::Sampled(i, _)) => {
                cmd.use_image(i, access);
                (i.traffic_bytes(), false)
            }
            Some(Bound::Buffer(x)) => {
                cmd.use_buffer(x, access);
                (x.size(), x.host_visible())
            }
            Some(Bound::Part(x, _, bytes)) => {
                cmd.use_buffer(x, access);
                (*bytes, x.host_visible())
            }
            Some(Bound::Set(_)) | None => (0, false),
        };
        let bytes = if referenced.has(i) { bytes } else { 0 };
        let (read, write) = match b.kind {
            BindKind::Sampled(_) | BindKind::Uniform => (true, false),
            BindKind::StorageImage(u) | BindKind::StorageBuffer(u) => {
                (u != Use::Write, u != Use::Read)
            }
        };
        if bytes > 0 {
            tracing::debug!(
                target: "cbr::traffic",
                "{}: `{}` {bytes} bytes{}{}",
                referenced.pass,
                b.name,
                if read { " read" } else { "" },
                if write { " written" } else { "" }
            );
        }
        t.bytes_read += if read { bytes } else { 0 };
        t.bytes_written += if write { bytes } else { 0 };
        t.host_bytes_written += if write && host { bytes } else { 0 };
    }
    cmd.add_traffic(&t);
}

/// Whether `r` is the shared set named `name`.
fn shared_named(r: &SetRef, name: &str) -> bool {
    matches!(r, SetRef::Shared(s) if s.name == name)
}

/// A ping-pong pair: frame f writes slot f % 2 and reads the other (written by frame f - 1).
pub struct History<T> {
    slots: [T; 2],
}

impl<T> History<T> {
    pub fn new(mut make: impl FnMut(usize) -> Result<T>) -> Result<History<T>> {
        Ok(History {
            slots: [make(0)?, make(1)?],
        })
    }

    /// The slot frame `frame` writes (and the next frame reads).
    pub fn write(&self, frame: u32) -> &T {
        &self.slots[frame as usize % 2]
    }

    /// The slot frame `frame` reads: the one frame `frame - 1` wrote.
    pub fn read(&self, frame: u32) -> &T {
        &self.slots[(frame as usize + 1) % 2]
    }

    /// Slot `k` (passes that pick their slot themselves: the resolve's frame parity).
    pub fn slot(&self, k: usize) -> &T {
        &self.slots[k % 2]
    }
}

/// One resource a technique or pass owns, declared once: allocation and memory estimate come
/// from it.
#[derive(Clone, Debug)]
pub struct ResourceDecl {
    /// The binding name it is bound under; allocated as `<owner>.<name>` (`[0]`, `[1]` for a
    /// history's slots).
    pub name: &'static str,
    pub kind: ResourceKind,
    /// A ping-pong pair ([`History`]).
    pub history: bool,
}

/// Where a declared buffer lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Memory {
    Device,
    /// Host-visible, written by the host before the frame (lights, patterns).
    Upload,
    /// Host-visible, read by the host after the frame.
    Host,
}

#[derive(Clone, Debug)]
pub enum ResourceKind {
    Image {
        format: vk::Format,
        width: u32,
        height: u32,
        usage: vk::ImageUsageFlags,
        samples: u32,
        /// Array layers (the split layout's two).
        layers: u32,
        flags: vk::ImageCreateFlags,
    },
    /// A host-visible buffer an image of `format`, `width` x `height` x `layers` is copied into
    /// after the frame (`Readback`).
    Readback {
        format: vk::Format,
        width: u32,
        height: u32,
        layers: u32,
    },
    /// A buffer in `memory`.
    Buffer {
        bytes: u64,
        usage: vk::BufferUsageFlags,
        memory: Memory,
    },
}

impl ResourceDecl {
    /// A `width` x `height` image of `format` (STORAGE, SAMPLED and TRANSFER_SRC: written by a
    /// pass, read by the next or a post pass, read back).
    pub fn image(name: &'static str, format: vk::Format, width: u32, height: u32) -> ResourceDecl {
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC;
        ResourceDecl::image_of(name, format, (width, height), usage, 1)
    }

    fn image_of(
        name: &'static str,
        format: vk::Format,
        (width, height): (u32, u32),
        usage: vk::ImageUsageFlags,
        samples: u32,
    ) -> ResourceDecl {
        ResourceDecl {
            name,
            kind: ResourceKind::Image {
                format,
                width,
                height,
                usage,
                samples,
                layers: 1,
                flags: vk::ImageCreateFlags::empty(),
            },
            history: false,
        }
    }

    /// The readback of a `width` x `height` image of `format` (one layer: see
    /// [`ResourceDecl::layers`]).
    pub fn readback(
        name: &'static str,
        format: vk::Format,
        width: u32,
        height: u32,
    ) -> ResourceDecl {
        ResourceDecl {
            name,
            kind: ResourceKind::Readback {
                format,
                width,
                height,
                layers: 1,
            },
            history: false,
        }
    }

    /// With `n` array layers (an image, or the readback of one).
    pub fn layers(mut self, n: u32) -> ResourceDecl {
        match &mut self.kind {
            ResourceKind::Image { layers, .. } | ResourceKind::Readback { layers, .. } => {
                *layers = n
            }
            ResourceKind::Buffer { .. } => {}
        }
        self
    }

    /// An image with creation flags (a depth target compatible with custom sample locations).
    pub fn flags(mut self, more: vk::ImageCreateFlags) -> ResourceDecl {
        if let ResourceKind::Image { flags, .. } = &mut self.kind {
            *flags |= more;
        }
        self
    }

    /// Allocates this image as `<owner>.<name>` (for structs that keep their images in fields,
    /// like the frame targets: the declaration is still the one description).
    pub fn make_image(&self, gpu: &Gpu, owner: &str) -> Result<Image> {
        match self.make(gpu, &self.slot_names(owner)[0])? {
            Owned::Image(i) => Ok(i),
            _ => Err(declaration(
                owner,
                format!("`{}` is not an image", self.name),
            )),
        }
    }

    /// Allocates this readback as `<owner>.<name>`.
    pub fn make_readback(&self, gpu: &Gpu, owner: &str) -> Result<Readback> {
        match self.make(gpu, &self.slot_names(owner)[0])? {
            Owned::Readback(r) => Ok(r),
            _ => Err(declaration(
                owner,
                format!("`{}` is not a readback", self.name),
            )),
        }
    }

    fn make(&self, gpu: &Gpu, name: &str) -> Result<Owned> {
        Ok(match &self.kind {
            ResourceKind::Image {
                format,
                width,
                height,
                usage,
                samples,
                layers,
                flags,
            } => Owned::Image(Image::new(
                gpu,
                &ImageDesc {
                    samples: *samples,
                    layers: *layers,
                    flags: *flags,
                    ..ImageDesc::new_2d(name, *format, *width, *height, *usage)
                },
            )?),
            ResourceKind::Buffer {
                bytes,
                usage,
                memory,
            } => Owned::Buffer(Buffer::new(
                gpu,
                name,
                *bytes,
                *usage,
                match memory {
                    Memory::Device => cbr_gpu::Location::GpuOnly,
                    Memory::Upload => cbr_gpu::Location::CpuToGpu,
                    Memory::Host => cbr_gpu::Location::GpuToCpu,
                },
            )?),
            ResourceKind::Readback {
                format,
                width,
                height,
                layers,
            } => Owned::Readback(Readback::for_buffer(
                gpu,
                name,
                readback_bytes(*format, *width, *height, *layers),
                *width,
                *height,
            )?),
        })
    }

    /// A render target of `samples` samples a raster pass writes and a later pass samples
    /// (colour, or depth for a depth format: not sampled).
    pub fn attachment(
        name: &'static str,
        format: vk::Format,
        width: u32,
        height: u32,
        samples: u32,
    ) -> ResourceDecl {
        let usage = if cbr_gpu::resource::is_depth_format(format) {
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED
        };
        ResourceDecl::image_of(name, format, (width, height), usage, samples)
    }

    /// A storage buffer of `bytes`.
    pub fn buffer(name: &'static str, bytes: u64) -> ResourceDecl {
        ResourceDecl {
            name,
            kind: ResourceKind::Buffer {
                bytes,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_SRC
                    | vk::BufferUsageFlags::TRANSFER_DST,
                memory: Memory::Device,
            },
            history: false,
        }
    }

    /// A host-visible storage buffer of `bytes` the host reads after the frame.
    pub fn host_buffer(name: &'static str, bytes: u64) -> ResourceDecl {
        ResourceDecl::buffer_in(
            name,
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            Memory::Host,
        )
    }

    /// A host-visible storage buffer of `bytes` the host writes before the frame.
    pub fn upload_buffer(name: &'static str, bytes: u64) -> ResourceDecl {
        ResourceDecl::buffer_in(
            name,
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            Memory::Upload,
        )
    }

    /// A host-visible buffer of `bytes` a buffer is copied into after the frame.
    pub fn readback_buffer(name: &'static str, bytes: u64) -> ResourceDecl {
        ResourceDecl::buffer_in(
            name,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            Memory::Host,
        )
    }

    /// A buffer of `bytes` with `usage` in `memory`.
    pub fn buffer_in(
        name: &'static str,
        bytes: u64,
        usage: vk::BufferUsageFlags,
        memory: Memory,
    ) -> ResourceDecl {
        ResourceDecl {
            name,
            kind: ResourceKind::Buffer {
                bytes,
                usage,
                memory,
            },
            history: false,
        }
    }

    /// Allocates this buffer as `<owner>.<name>`.
    pub fn make_buffer(&self, gpu: &Gpu, owner: &str) -> Result<Buffer> {
        match self.make(gpu, &self.slot_names(owner)[0])? {
            Owned::Buffer(b) => Ok(b),
            _ => Err(declaration(
                owner,
                format!("`{}` is not a buffer", self.name),
            )),
        }
    }

    /// A buffer with more usages (one copied from: TRANSFER_SRC).
    pub fn buffer_usage(mut self, more: vk::BufferUsageFlags) -> ResourceDecl {
        if let ResourceKind::Buffer { usage, .. } = &mut self.kind {
            *usage |= more;
        }
        self
    }

    /// With more usages (an image another pass fills by a copy: TRANSFER_DST).
    pub fn usage(mut self, more: vk::ImageUsageFlags) -> ResourceDecl {
        if let ResourceKind::Image { usage, .. } = &mut self.kind {
            *usage |= more;
        }
        self
    }

    /// A buffer also read as an indirect dispatch's parameters (INDIRECT_BUFFER).
    pub fn indirect(mut self) -> ResourceDecl {
        if let ResourceKind::Buffer { usage, .. } = &mut self.kind {
            *usage |= vk::BufferUsageFlags::INDIRECT_BUFFER;
        }
        self
    }

    /// As a ping-pong pair.
    pub fn history(mut self) -> ResourceDecl {
        self.history = true;
        self
    }

    fn slot_names(&self, owner: &str) -> Vec<String> {
        if self.history {
            (0..2)
                .map(|i| format!("{owner}.{}[{i}]", self.name))
                .collect()
        } else {
            vec![format!("{owner}.{}", self.name)]
        }
    }

    /// What allocating it takes (crate::memory), under the names [`Resources::new`] uses.
    pub fn estimate(&self, e: &mut MemoryEstimate, owner: &str) {
        for name in self.slot_names(owner) {
            match &self.kind {
                ResourceKind::Image {
                    format,
                    width,
                    height,
                    samples,
                    layers,
                    ..
                } => e.image_array(name, *format, *width, *height, *layers, *samples),
                ResourceKind::Buffer {
                    bytes,
                    usage,
                    memory,
                } => {
                    let host = *memory != Memory::Device;
                    if usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) {
                        e.storage_buffer(name, *bytes, host)
                    } else {
                        e.buffer(name, *bytes, host)
                    }
                }
                ResourceKind::Readback {
                    format,
                    width,
                    height,
                    layers,
                } => e.readback(name, *format, *width, *height, *layers),
            }
        }
    }
}

/// The estimate of a list of declarations.
pub fn estimate(decls: &[ResourceDecl], owner: &str) -> MemoryEstimate {
    let mut e = MemoryEstimate::new();
    for d in decls {
        d.estimate(&mut e, owner);
    }
    e
}

enum Owned {
    Image(Image),
    Buffer(Buffer),
    Readback(Readback),
    History(History<Image>),
}

/// Bytes of the readback of a `width` x `height` x `layers` image of `format`.
fn readback_bytes(format: vk::Format, width: u32, height: u32, layers: u32) -> u64 {
    u64::from(width) * u64::from(height) * u64::from(layers) * crate::memory::texel_bytes(format)
}

/// The resources of one owner, allocated from their declarations, found by name.
pub struct Resources {
    owner: String,
    items: Vec<(&'static str, Owned)>,
    decls: Vec<ResourceDecl>,
}

impl Resources {
    pub fn new(gpu: &Gpu, owner: &str, decls: &[ResourceDecl]) -> Result<Resources> {
        let mut items = Vec::with_capacity(decls.len());
        for d in decls {
            if items.iter().any(|(n, _)| *n == d.name) {
                return Err(declaration(owner, format!("resource `{}` twice", d.name)));
            }
            let names = d.slot_names(owner);
            let make = |name: &str| d.make(gpu, name);
            let owned = if d.history {
                let image = |o: Owned| match o {
                    Owned::Image(i) => Ok(i),
                    _ => Err(declaration(
                        owner,
                        format!("history `{}` of buffers", d.name),
                    )),
                };
                Owned::History(History::new(|i| image(make(&names[i])?))?)
            } else {
                make(&names[0])?
            };
            items.push((d.name, owned));
        }
        Ok(Resources {
            owner: owner.to_string(),
            items,
            decls: decls.to_vec(),
        })
    }

    /// Replaces the buffer `name` by one of `bytes` with its declared usage and location: a
    /// buffer that grows to what a frame needed (analytic's tail records and albedo jobs). The
    /// estimate ([`estimate`]) is its declared size, the size it starts with. The old buffer must
    /// not be in use by a command buffer that has not completed; the declared passes make their
    /// descriptor sets per dispatch, so their next dispatch binds the new one.
    pub fn grow(&mut self, gpu: &Gpu, name: &str, bytes: u64) -> Result<()> {
        let owner = &self.owner;
        let i = self
            .items
            .iter()
            .position(|(n, o)| *n == name && matches!(o, Owned::Buffer(_)))
            .ok_or_else(|| declaration(owner, format!("no buffer `{name}` to grow")))?;
        let mut d = self.decls[i].clone();
        if let ResourceKind::Buffer { bytes: b, .. } = &mut d.kind {
            *b = bytes;
        }
        let new = d.make(gpu, &d.slot_names(owner)[0])?;
        self.items[i].1 = new;
        Ok(())
    }

    fn find(&self, name: &str) -> Result<&Owned> {
        self.items
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, o)| o)
            .ok_or_else(|| declaration(&self.owner, format!("no resource `{name}`")))
    }

    pub fn readback(&self, name: &str) -> Result<&Readback> {
        match self.find(name)? {
            Owned::Readback(r) => Ok(r),
            _ => Err(declaration(
                &self.owner,
                format!("`{name}` is not a readback"),
            )),
        }
    }

    pub fn image(&self, name: &str) -> Result<&Image> {
        match self.find(name)? {
            Owned::Image(i) => Ok(i),
            _ => Err(declaration(
                &self.owner,
                format!("`{name}` is not an image"),
            )),
        }
    }

    /// A buffer to write from the host (an upload buffer).
    pub fn buffer_mut(&mut self, name: &str) -> Result<&mut Buffer> {
        let owner = &self.owner;
        let found = self
            .items
            .iter_mut()
            .find(|(n, _)| *n == name)
            .map(|(_, o)| o)
            .ok_or_else(|| declaration(owner, format!("no resource `{name}`")))?;
        match found {
            Owned::Buffer(b) => Ok(b),
            _ => Err(declaration(owner, format!("`{name}` is not a buffer"))),
        }
    }

    pub fn buffer(&self, name: &str) -> Result<&Buffer> {
        match self.find(name)? {
            Owned::Buffer(b) => Ok(b),
            _ => Err(declaration(
                &self.owner,
                format!("`{name}` is not a buffer"),
            )),
        }
    }

    pub fn history(&self, name: &str) -> Result<&History<Image>> {
        match self.find(name)? {
            Owned::History(h) => Ok(h),
            _ => Err(declaration(
                &self.owner,
                format!("`{name}` is not a history"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    push_constants! {
        struct TestPush {
            size: [i32; 4],
            scale: f32,
            count: u32,
            pad: [f32; 2],
            taps: [f32; 3] as array,
        }
    }

    #[test]
    fn push_constants_give_their_glsl_block() {
        assert_eq!(
            TestPush::glsl(),
            "layout(push_constant) uniform Push { ivec4 size; float scale; uint count; \
             vec2 pad; float taps[3]; } pc;"
        );
        assert_eq!(std::mem::size_of::<TestPush>(), 44);
    }

    #[test]
    fn bindings_are_numbered_by_position_and_named_in_defines() {
        let d = ComputeDecl::new("t", "t.comp")
            .bind(Binding::sampled("src"))
            .bind(Binding::image("dst", Use::Write))
            .bind(Binding::buffer("list", Use::Read))
            .constants(&[("FLAG_X", 4)])
            .push::<TestPush>()
            .group(16, 4);
        let defs = d.all_defines();
        let get = |k: &str| defs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        assert_eq!(get("BINDING_SRC").as_deref(), Some("0"));
        assert_eq!(get("BINDING_DST").as_deref(), Some("1"));
        assert_eq!(get("BINDING_LIST").as_deref(), Some("2"));
        assert_eq!(get("FLAG_X").as_deref(), Some("4u"));
        assert_eq!(get("LOCAL_SIZE_X").as_deref(), Some("16"));
        assert_eq!(get("LOCAL_SIZE_Y").as_deref(), Some("4"));
        assert!(get("PUSH_CONSTANTS").is_some_and(|p| p.contains("float scale;")));
        let dup = ComputeDecl::new("t", "t.comp")
            .bind(Binding::sampled("src"))
            .bind(Binding::sampled("src"));
        assert!(dup.check().is_err());
    }

    /// Every declared pass's push-constant block: the offsets glslang gives its members (the
    /// SPIR-V's Offset decorations of the `Push` block) are the Rust struct's.
    #[test]
    fn push_constant_offsets_are_the_shaders() {
        use crate::layouts::LayoutPlan;
        use crate::resolve::{self, ResolveSettings};
        use crate::techniques::{checkerboard::unpack, deferred, interleaved, msaa, ssaa, upscale};
        let shaders = crate::shader_library();
        let plan = LayoutPlan::new(cbr_gpu::Layout::Rotated, 64, 36, 0);
        let interleaved = interleaved::parse(&["4x4", "direct"]).expect("interleaved");
        let mut decls = vec![
            crate::post::sharpen::decl(),
            crate::post::taa::decl(&crate::post::taa::TaaConfig::OURS, false),
            ssaa::decl(),
            resolve::decl(&ResolveSettings::default(), &plan, false),
            resolve::copy_floor_decl("copy"),
            unpack::decl(&plan),
            upscale::decl(upscale::UpscaleFilter::Bicubic),
            msaa::decl(msaa::parse(&["4"]).expect("msaa")),
            crate::techniques::interlaced::resolve::decl(&Default::default()),
            deferred::lighting::decl(None),
            deferred::rsm::vpl_decl(),
        ];
        decls.extend(crate::post::fxaa::decls());
        decls.extend(interleaved::split::decls(&interleaved));
        let analytic = crate::techniques::analytic::parse(&[]).expect("analytic");
        let k = crate::techniques::analytic::Kernel::new(analytic, 64, 36, 1 << 27).expect("fits");
        decls.extend(crate::techniques::analytic::decls(&k));
        /// A pass's name, one of its shaders with its defines, and its push-constant members.
        type Stage<'a> = (String, &'a str, Vec<(String, String)>, &'a [PushField]);
        let mut stages: Vec<Stage> = decls
            .iter()
            .filter(|d| d.push.is_some())
            .map(|d| (d.name.clone(), d.shader, d.all_defines(), d.push_fields))
            .collect();
        // The raster passes' blocks, in every stage that declares them.
        let mut rasters = crate::scene_pass::decls(
            "scene",
            &crate::scene_pass::RasterConfig::native(64, 36),
            &[],
        )
        .expect("scene pass");
        rasters.extend(crate::techniques::analytic::raster_decls(&k, &[]));
        for d in rasters.iter().chain([&deferred::rsm::decl()]) {
            for (shader, defines) in d.stages() {
                stages.push((d.name.clone(), shader, defines, d.push_fields));
            }
        }
        for raster in [
            "scene/forward.vert",
            "scene/forward.frag",
            "deferred/rsm.vert",
            "analytic/raster.frag",
        ] {
            assert!(stages.iter().any(|s| s.1 == raster), "{raster} not checked");
        }
        // A raster stage that declares no push block (analytic's raster.geom) is skipped; every
        // pass must have a stage that declares it.
        let mut checked: Vec<String> = Vec::new();
        let names: Vec<String> = stages.iter().map(|s| s.0.clone()).collect();
        for (name, shader, defines, fields) in stages {
            let words = shaders
                .compile(shader, &defines)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let offsets = crate::gpu_types::tests::member_offsets(&words);
            if shader.ends_with(".geom") && !offsets.keys().any(|(block, _)| block == "Push") {
                continue;
            }
            checked.push(name.clone());
            for (i, f) in fields.iter().enumerate() {
                let glsl = offsets.get(&("Push".to_string(), i as u32)).copied();
                assert_eq!(
                    glsl,
                    Some(f.offset as u32),
                    "{name}: push constant `{}`",
                    f.name
                );
            }
        }
        for name in names {
            assert!(
                checked.contains(&name),
                "{name}: no stage declares its push block"
            );
        }
    }

    #[test]
    fn history_slots_alternate() {
        let h = History::new(Ok).expect("history");
        assert_eq!((*h.write(0), *h.read(0)), (0, 1));
        assert_eq!((*h.write(1), *h.read(1)), (1, 0));
        assert_eq!((*h.write(6), *h.read(7)), (0, 0));
    }

    #[test]
    fn estimates_name_what_is_allocated() {
        let decls = [
            ResourceDecl::image("out", vk::Format::R16G16B16A16_SFLOAT, 4, 2),
            ResourceDecl::image("hist", vk::Format::R32G32_UINT, 4, 2).history(),
            ResourceDecl::buffer("list", 100),
        ];
        let e = estimate(&decls, "p");
        let names: Vec<&str> = e.items.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["p.out", "p.hist[0]", "p.hist[1]", "p.list"]);
        assert_eq!(e.items[0].bytes, 64);
        assert_eq!(e.items[1].bytes, 64);
        assert_eq!(e.items[3].bytes, 100);
    }
}
