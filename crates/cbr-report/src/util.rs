//! Shared helpers: HTML escaping, relative links, number formatting, the series palette.

use std::path::{Component, Path, PathBuf};

use serde_json::Value;

/// Colours for passes (timing bars) and configurations (error curves).
pub(crate) const PALETTE: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
];

/// Escapes text for HTML element content and double-quoted attributes.
pub(crate) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `to` relative to the folder `from` (both made absolute against the working directory).
pub fn relative(from: &Path, to: &Path) -> PathBuf {
    let abs = |p: &Path| {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                Component::ParentDir => {
                    out.pop();
                }
                Component::CurDir => {}
                c => out.push(c),
            }
        }
        out
    };
    let (f, t) = (abs(from), abs(to));
    let fc: Vec<_> = f.components().collect();
    let tc: Vec<_> = t.components().collect();
    let common = fc.iter().zip(&tc).take_while(|(a, b)| a == b).count();
    let mut r = PathBuf::new();
    for _ in common..fc.len() {
        r.push("..");
    }
    for c in &tc[common..] {
        r.push(c);
    }
    r
}

/// A relative path as a URL path (`/` separators, spaces escaped).
pub(crate) fn url(p: &Path) -> String {
    p.components()
        .map(|c| c.as_os_str().to_string_lossy().replace(' ', "%20"))
        .collect::<Vec<_>>()
        .join("/")
}

/// A finite JSON number.
pub(crate) fn num(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite())
}

/// A number with `digits` decimals, or a dash when missing.
pub(crate) fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_and_escaping() {
        assert_eq!(
            relative(Path::new("/a/b"), Path::new("/a/c/d.png")),
            PathBuf::from("../c/d.png")
        );
        assert_eq!(
            relative(Path::new("/a"), Path::new("/a/x.json")),
            PathBuf::from("x.json")
        );
        assert_eq!(esc("<a&\"b\">"), "&lt;a&amp;&quot;b&quot;&gt;");
        assert_eq!(url(Path::new("../a b/c.png")), "../a%20b/c.png");
        assert_eq!(fmt(Some(1.23456), 2), "1.23");
        assert_eq!(fmt(None, 2), "–");
    }
}
