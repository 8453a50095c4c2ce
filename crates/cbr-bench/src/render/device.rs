//! What `cbr info` says about the device's support of particular techniques: the checkerboard
//! layouts it can run and msaa2x's sample locations.

use cbr_gpu::{Caps, Layout};
use serde_json::{Value, json};

/// Per layout: its name, whether the device runs it, and what it misses (`cbr info --json`).
pub fn layouts_json(caps: &Caps) -> Vec<Value> {
    Layout::ALL
        .iter()
        .map(|&l| {
            json!({
                "layout": l.name(),
                "supported": caps.layout_unsupported(l).is_none(),
                "missing": caps.layout_unsupported(l),
            })
        })
        .collect()
}

/// The text section on layouts, heading first, one line per row.
pub fn layouts_text(caps: &Caps) -> Vec<String> {
    let mut lines = vec!["\ncheckerboard layouts:".to_string()];
    for l in Layout::ALL {
        lines.push(match caps.layout_unsupported(l) {
            None => format!("  {:8} yes", l.name()),
            Some(why) => format!("  {:8} no: needs {why}", l.name()),
        });
    }
    lines.push(match caps.sample_locations_unsupported() {
        None => "  msaa2x --msaa2x-sample-locations yes".to_string(),
        Some(why) => format!("  msaa2x --msaa2x-sample-locations no: needs {why}"),
    });
    if caps.layout_unsupported(Layout::Msaa2x).is_some() {
        let portable: Vec<&str> = caps.supported_layouts().iter().map(|l| l.name()).collect();
        lines.push(format!(
            "  (msaa2x needs 2x MSAA; on this device use the portable layouts: {})",
            portable.join(", ")
        ));
    }
    lines
}
