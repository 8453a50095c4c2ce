//! Raster passes declared once: one [`GraphicsDecl`] per pipeline (its shaders and defines, its
//! sets, push constants, attachments by name and format, and its fixed-function state). From it
//! come the set layouts and the pipeline ([`GraphicsDecl::build`]: compile-only, like a compute
//! pass's), every shader-side number (`BINDING_<NAME>`, `SET_<NAME>`, `PUSH_CONSTANTS`), and at
//! record time the checked binds, their barriers and the attachments by name.

use super::{
    BTreeMap, BindKind, Binding, Binds, Bound, PushConstants, PushField, Referenced, SetDecl,
    SetRef, check_binds, check_sets, declaration, make_set, record_uses, samplers, set_defines,
    set_layouts,
};
use cbr_gpu::{Cmd, Gpu, GraphicsDesc, Image, Pipeline, Result, Sampler, SetLayout, Shaders, vk};

/// The fixed-function state of a raster pipeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterState {
    pub depth_compare: vk::CompareOp,
    pub depth_write: bool,
    pub samples: u32,
    /// Shade every sample (`minSampleShading = 1`).
    pub sample_shading: bool,
    pub cull_back_faces: bool,
    /// Custom sample locations, set per frame (VK_EXT_sample_locations dynamic state).
    pub sample_locations: bool,
}

impl Default for RasterState {
    /// Reverse-Z (nearer is larger: GREATER, writing), one sample, no culling.
    fn default() -> RasterState {
        RasterState {
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            samples: 1,
            sample_shading: false,
            cull_back_faces: false,
            sample_locations: false,
        }
    }
}

/// One raster pipeline, declared once.
#[derive(Clone, Debug)]
pub struct GraphicsDecl {
    /// The pipeline's name (debug utils).
    pub name: String,
    /// Paths under `shaders/`.
    pub vertex: &'static str,
    pub geometry: Option<&'static str>,
    pub fragment: &'static str,
    /// Defines of every stage.
    pub defines: Vec<(String, String)>,
    /// Defines of the fragment stage only (a material variant's `MAT_FEATURES`, ...).
    pub fragment_defines: Vec<(String, String)>,
    /// The pass's own set (bound from [`Binds`] by [`GraphicsPass::bind`]).
    pub bindings: Vec<Binding>,
    /// The pipeline layout's sets in order ([`GraphicsDecl::shared`], [`GraphicsDecl::own_set`]).
    pub sets: Vec<SetRef>,
    pub push: Option<(u32, String)>,
    pub push_fields: &'static [PushField],
    /// Colour attachments in location order, by name, and the depth attachment.
    pub colors: Vec<(&'static str, vk::Format)>,
    pub depth: Option<(&'static str, vk::Format)>,
    pub state: RasterState,
}

impl GraphicsDecl {
    pub fn new(name: impl Into<String>, vertex: &'static str, fragment: &'static str) -> Self {
        GraphicsDecl {
            name: name.into(),
            vertex,
            geometry: None,
            fragment,
            defines: Vec::new(),
            fragment_defines: Vec::new(),
            bindings: Vec::new(),
            sets: Vec::new(),
            push: None,
            push_fields: &[],
            colors: Vec::new(),
            depth: None,
            state: RasterState::default(),
        }
    }

    pub fn geometry(mut self, shader: &'static str) -> Self {
        self.geometry = Some(shader);
        self
    }

    pub fn define(mut self, name: &str, value: impl ToString) -> Self {
        self.defines.push((name.to_string(), value.to_string()));
        self
    }

    /// A define of the fragment stage only.
    pub fn fragment_define(mut self, name: &str, value: impl ToString) -> Self {
        self.fragment_defines
            .push((name.to_string(), value.to_string()));
        self
    }

    /// A shared set at the next set index.
    pub fn shared(mut self, set: SetDecl) -> Self {
        self.sets.push(SetRef::Shared(set));
        self
    }

    /// The own set at the next set index, holding `bindings`.
    pub fn own_set(mut self, bindings: &[Binding]) -> Self {
        self.sets.push(SetRef::Own);
        self.bindings.extend_from_slice(bindings);
        self
    }

    pub fn push<P: PushConstants>(mut self) -> Self {
        self.push = Some((std::mem::size_of::<P>() as u32, P::glsl()));
        self.push_fields = P::FIELDS;
        self
    }

    pub fn color(mut self, name: &'static str, format: vk::Format) -> Self {
        self.colors.push((name, format));
        self
    }

    pub fn depth(mut self, name: &'static str, format: vk::Format) -> Self {
        self.depth = Some((name, format));
        self
    }

    pub fn state(mut self, state: RasterState) -> Self {
        self.state = state;
        self
    }

    /// The defines of the vertex and geometry stages.
    pub fn stage_defines(&self) -> Vec<(String, String)> {
        let mut d = self.defines.clone();
        d.extend(set_defines(&self.sets, &self.bindings));
        if let Some((_, glsl)) = &self.push {
            d.push(("PUSH_CONSTANTS".into(), glsl.clone()));
        }
        d
    }

    /// The defines of the fragment stage.
    pub fn fragment_stage_defines(&self) -> Vec<(String, String)> {
        let mut d = self.stage_defines();
        d.extend(self.fragment_defines.iter().cloned());
        d
    }

    /// Every shader the pipeline compiles, with its defines (the compile-only list's entries).
    pub fn stages(&self) -> Vec<(&'static str, Vec<(String, String)>)> {
        let mut s = vec![(self.vertex, self.stage_defines())];
        if let Some(g) = self.geometry {
            s.push((g, self.stage_defines()));
        }
        s.push((self.fragment, self.fragment_stage_defines()));
        s
    }

    fn check(&self) -> Result<()> {
        check_sets(&self.name, &self.sets, &self.bindings)?;
        if let Some(b) = self
            .bindings
            .iter()
            .find(|b| matches!(b.kind, BindKind::StorageImage(_)))
        {
            return Err(declaration(
                &self.name,
                format!(
                    "`{}`: storage images are not declared for raster passes",
                    b.name
                ),
            ));
        }
        let names: Vec<&str> = self
            .colors
            .iter()
            .map(|c| c.0)
            .chain(self.depth.map(|d| d.0))
            .collect();
        for (i, n) in names.iter().enumerate() {
            if names[..i].contains(n) {
                return Err(declaration(&self.name, format!("attachment `{n}` twice")));
            }
        }
        Ok(())
    }

    /// The compile-only build: set layouts, samplers and pipeline; no image, no memory.
    pub fn build(&self, gpu: &Gpu, shaders: &Shaders) -> Result<GraphicsPass> {
        self.check()?;
        let layouts = set_layouts(gpu, &self.name, &self.sets, &self.bindings)?;
        let vs = shaders.compile(self.vertex, &self.stage_defines())?;
        let gs = match self.geometry {
            Some(g) => Some(shaders.compile(g, &self.stage_defines())?),
            None => None,
        };
        let fs = shaders.compile(self.fragment, &self.fragment_stage_defines())?;
        let colors: Vec<vk::Format> = self.colors.iter().map(|c| c.1).collect();
        let s = self.state;
        let pipeline = Pipeline::graphics(
            gpu,
            &GraphicsDesc {
                name: &self.name,
                vertex: &vs,
                geometry: gs.as_ref().map(|g| g.as_slice()),
                fragment: &fs,
                set_layouts: &layouts.iter().collect::<Vec<_>>(),
                push_constant_bytes: self.push.as_ref().map_or(0, |p| p.0),
                color_formats: &colors,
                depth_format: self.depth.map(|d| d.1),
                depth_compare: s.depth_compare,
                depth_write: s.depth_write,
                samples: s.samples,
                min_sample_shading: s.sample_shading.then_some(1.0),
                cull_back_faces: s.cull_back_faces,
                sample_locations: s.sample_locations,
            },
        )?;
        let samplers = samplers(gpu, &self.name, &self.bindings)?;
        let own = self
            .sets
            .iter()
            .position(|r| *r == SetRef::Own)
            .unwrap_or(0) as u32;
        let mut modules = vec![vs.as_slice(), fs.as_slice()];
        modules.extend(gs.as_ref().map(|g| g.as_slice()));
        Ok(GraphicsPass {
            decl: self.clone(),
            layouts,
            pipeline,
            samplers,
            referenced: Referenced::of(&self.name, &modules, own),
        })
    }
}

/// A built raster pass: pipeline, set layouts and the samplers of its own sampled bindings.
pub struct GraphicsPass {
    pub decl: GraphicsDecl,
    layouts: Vec<SetLayout>,
    pipeline: Pipeline,
    samplers: BTreeMap<u8, Sampler>,
    referenced: Referenced,
}

impl GraphicsPass {
    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    /// The index of the shared set `name` in the pipeline layout.
    pub fn set_index(&self, name: &str) -> Result<u32> {
        self.decl
            .sets
            .iter()
            .position(|r| matches!(r, SetRef::Shared(s) if s.name == name))
            .map(|i| i as u32)
            .ok_or_else(|| declaration(&self.decl.name, format!("no shared set `{name}`")))
    }

    /// The layout of the shared set `name` (to make its sets with [`SetDecl::make`]: every
    /// pass's layout of one declaration is identically defined, so the sets bind with any).
    pub fn layout(&self, name: &str) -> Result<&SetLayout> {
        Ok(&self.layouts[self.set_index(name)? as usize])
    }

    fn own_index(&self) -> Option<usize> {
        self.decl.sets.iter().position(|r| *r == SetRef::Own)
    }

    /// Checks `binds` against the own set and records the barriers its declared uses need
    /// (before rendering begins). Shared sets' resources are barriered by their owner.
    pub fn prepare(&self, cmd: &mut Cmd, binds: &Binds) -> Result<()> {
        let d = &self.decl;
        for name in binds.explicit() {
            let known = d.bindings.iter().any(|b| b.name == name)
                || d.colors.iter().any(|c| c.0 == name)
                || d.depth.is_some_and(|x| x.0 == name)
                || d.sets.iter().any(|r| super::shared_named(r, name));
            if !known {
                return Err(declaration(
                    &d.name,
                    format!("`{name}` is bound but not declared"),
                ));
            }
        }
        let own = binds.own_only(&self.decl.bindings);
        check_binds(&self.decl.name, &self.decl.bindings, &own)?;
        record_uses(
            cmd,
            &self.decl.bindings,
            &own,
            BindKind::graphics_access,
            &self.referenced,
        );
        Ok(())
    }

    /// Binds the pipeline, its own set (made from `binds`, kept by the command buffer) and the
    /// shared sets `binds` give (sets not given, like a material's, are bound per draw).
    pub fn bind(&self, cmd: &mut Cmd, binds: &Binds) -> Result<()> {
        cmd.bind_pipeline(&self.pipeline);
        if let Some(i) = self.own_index() {
            let set = make_set(
                cmd.gpu(),
                &self.decl.name,
                &self.layouts[i],
                &self.decl.bindings,
                &binds.own_only(&self.decl.bindings),
                &self.samplers,
            )?;
            cmd.bind_set(&self.pipeline, i as u32, &set);
            cmd.keep(set);
        }
        for (i, r) in self.decl.sets.iter().enumerate() {
            if let SetRef::Shared(s) = r
                && let Some(Bound::Set(set)) = binds.get(s.name)
            {
                cmd.bind_set(&self.pipeline, i as u32, set);
            }
        }
        Ok(())
    }

    /// The colour attachments (in location order) and the depth attachment `binds` name, each
    /// checked against its declared format.
    pub fn attachments<'b>(
        &self,
        binds: &Binds<'b>,
    ) -> Result<(Vec<&'b Image>, Option<&'b Image>)> {
        let get = |name: &str, format: vk::Format| -> Result<&'b Image> {
            match binds.get(name) {
                Some(Bound::Image(i)) if i.format == format => Ok(*i),
                Some(Bound::Image(i)) => Err(declaration(
                    &self.decl.name,
                    format!(
                        "attachment `{name}` is {format:?}, given an image of {:?}",
                        i.format
                    ),
                )),
                _ => Err(declaration(
                    &self.decl.name,
                    format!("no image bound to attachment `{name}`"),
                )),
            }
        };
        let colors = self
            .decl
            .colors
            .iter()
            .map(|(n, f)| get(n, *f))
            .collect::<Result<Vec<_>>>()?;
        let depth = match self.decl.depth {
            Some((n, f)) => Some(get(n, f)?),
            None => None,
        };
        Ok((colors, depth))
    }
}
