//! The registries: every technique and every post pass, in the order `cbr render --help` and
//! errors list them. Adding one is its module, its shader folder and one line here. Nothing else
//! names a technique: the sequencer, the spec parser and the CLI look them up here.

use crate::post::PostRegistration;
use crate::spec::{Part, Spec};
use crate::technique::Registration;

/// Every technique, in the order `cbr render --help` and errors list them.
pub const TECHNIQUES: &[Registration] = &[
    crate::techniques::native::REGISTRATION,
    crate::techniques::ssaa::REGISTRATION,
    crate::techniques::msaa::REGISTRATION,
    crate::techniques::checkerboard::REGISTRATION,
    crate::techniques::upscale::REGISTRATION,
    crate::techniques::interlaced::REGISTRATION,
    crate::techniques::analytic::REGISTRATION,
    crate::techniques::deferred::REGISTRATION,
    crate::techniques::interleaved::REGISTRATION,
];

pub fn find(name: &str) -> Option<&'static Registration> {
    TECHNIQUES.iter().find(|t| t.name == name)
}

pub const POST_PASSES: &[PostRegistration] = &[
    crate::post::fxaa::REGISTRATION,
    crate::post::taa::REGISTRATION,
    crate::post::sharpen::REGISTRATION,
];

pub fn find_post(name: &str) -> Option<&'static PostRegistration> {
    POST_PASSES.iter().find(|p| p.name == name)
}

/// Specs are read against the registries (the grammar itself is crate::spec's).
impl Spec {
    /// Parses and checks a spec against the registries: an unknown name lists what is
    /// registered; a bad parameter is named by its registration.
    pub fn parse(text: &str) -> std::result::Result<Spec, String> {
        let mut parts = text.split('+');
        let head = crate::spec::split_part(parts.next().unwrap_or_default());
        let post: Vec<Part> = parts.map(crate::spec::split_part).collect();
        let t = find(&head.name).ok_or_else(|| {
            format!(
                "technique spec `{text}`: `{}` is no registered technique (registered: {})",
                head.name,
                TECHNIQUES
                    .iter()
                    .map(|t| t.grammar)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })?;
        (t.check)(&head.params()).map_err(|e| format!("technique spec `{text}`: {e}"))?;
        for p in &post {
            let pp = find_post(&p.name).ok_or_else(|| {
                format!(
                    "technique spec `{text}`: `+{}` is no registered post pass (registered: {})",
                    p.name,
                    POST_PASSES
                        .iter()
                        .map(|p| format!("+{}", p.grammar))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?;
            (pp.check)(&p.params()).map_err(|e| format!("technique spec `{text}`: {e}"))?;
        }
        Ok(Spec {
            technique: head,
            post,
        })
    }
}

/// The passes `spec` builds at the context's size, each declared once: the technique's compute
/// and raster passes, then each post pass's, in chain order. Building them (`ComputeDecl::build`,
/// `GraphicsDecl::build`) compiles every pipeline of the spec without an image, memory or a
/// command buffer.
pub fn passes(
    spec: &Spec,
    ctx: &crate::technique::PassCtx,
) -> std::result::Result<crate::technique::PassList, String> {
    let t = find(&spec.technique.name)
        .ok_or_else(|| format!("no technique `{}`", spec.technique.name))?;
    // A post pass that reads the frame's geometry makes the technique write it (BuildCtx too).
    let geometry = spec
        .post
        .iter()
        .any(|p| find_post(&p.name).is_some_and(|r| r.geometry));
    let ctx = crate::technique::PassCtx {
        geometry: ctx.geometry || geometry,
        ..*ctx
    };
    let mut list =
        (t.passes)(&ctx, &spec.technique.params()).map_err(|e| format!("`{spec}`: {e}"))?;
    for part in &spec.post {
        let p = find_post(&part.name).ok_or_else(|| format!("no post pass `+{}`", part.name))?;
        list.compute.extend(
            (p.passes)(&part.params(), list.packed_geometry)
                .map_err(|e| format!("`{spec}`: {e}"))?,
        );
    }
    Ok(list)
}
