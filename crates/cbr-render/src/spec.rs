//! The technique spec grammar, one for every command and file (render, bench, sweep TOMLs,
//! run.json, bench.json, the report):
//!
//! ```text
//! spec  = part ("+" part)*          the technique, then post passes in order
//! part  = name (":" param)*
//! ```
//!
//! `native`, `ssaa:16`, `msaa:4:sample`, `checkerboard:rotated:ours`,
//! `checkerboard:split:pq4k:prepass+sharpen:0.5`. The first part names a registered technique,
//! the others registered post passes (crate::registry::TECHNIQUES, crate::registry::POST_PASSES);
//! each registration reads its own parameters.

use std::fmt;

/// One `name:param:param` part of a spec.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    pub name: String,
    pub params: Vec<String>,
}

impl Part {
    pub fn params(&self) -> Vec<&str> {
        self.params.iter().map(String::as_str).collect()
    }
}

impl fmt::Display for Part {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)?;
        for p in &self.params {
            write!(f, ":{p}")?;
        }
        Ok(())
    }
}

/// A parsed, checked spec: a technique and its post chain.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Spec {
    pub technique: Part,
    pub post: Vec<Part>,
}

impl fmt::Display for Spec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.technique)?;
        for p in &self.post {
            write!(f, "+{p}")?;
        }
        Ok(())
    }
}

impl serde::Serialize for Spec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

pub(crate) fn split_part(text: &str) -> Part {
    let mut it = text.split(':').map(str::trim);
    Part {
        name: it.next().unwrap_or_default().to_string(),
        params: it.map(str::to_string).collect(),
    }
}

impl Spec {
    /// The spec of a technique without post passes (e.g. `native`).
    pub fn of(text: &str) -> Spec {
        let mut s = Spec {
            technique: split_part(text),
            post: Vec::new(),
        };
        if let Some((t, rest)) = text.split_once('+') {
            s.technique = split_part(t);
            s.post = rest.split('+').map(split_part).collect();
        }
        s
    }

    /// True when the technique part has `param` (e.g. `prepass`).
    pub fn has(&self, param: &str) -> bool {
        self.technique.params.iter().any(|p| p == param)
    }

    /// This spec with `param` appended to the technique part.
    pub fn with(mut self, param: &str) -> Spec {
        self.technique.params.push(param.to_string());
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_round_trip_and_bad_parts_are_named() {
        for s in [
            "native",
            "ssaa:16",
            "checkerboard:rotated:ours",
            "checkerboard:split:pq4k:prepass",
            "upscale:bicubic",
            "checkerboard:split:ours+sharpen",
            "native+sharpen:0.5+sharpen",
        ] {
            let spec = Spec::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"));
            assert_eq!(spec.to_string(), s);
            assert_eq!(Spec::of(s), spec);
        }
        let e = Spec::parse("hexagonal:4").unwrap_err();
        assert!(
            e.contains("`hexagonal`") && e.contains("native") && e.contains("ssaa"),
            "{e}"
        );
        let e = Spec::parse("native+blur").unwrap_err();
        assert!(e.contains("`+blur`") && e.contains("+sharpen"), "{e}");
        let e = Spec::parse("checkerboard:hexagon").unwrap_err();
        assert!(e.contains("`hexagon`"), "{e}");
        let e = Spec::parse("ssaa:0").unwrap_err();
        assert!(e.contains("ssaa"), "{e}");
        assert!(Spec::parse("native:extra").is_err());
    }
}
