//! The worst-FLIP crops: each crop window magnified for every panel, outlined on the reference.

use std::fmt::Write as _;

use serde_json::Value;

use crate::util::esc;

/// The crop windows (x, y, width, height) of a scene and resolution (from its first row).
pub(crate) fn windows(g: &[&Value]) -> Vec<[u64; 4]> {
    g.first()
        .and_then(|r| r["crops"].as_array())
        .map(|a| {
            a.iter()
                .filter_map(|c| {
                    let v: Vec<u64> = c.as_array()?.iter().filter_map(Value::as_u64).collect();
                    (v.len() == 4).then(|| [v[0], v[1], v[2], v[3]])
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The crop windows' outlines, drawn over the reference panel.
pub(crate) fn outlines(crops: &[[u64; 4]]) -> String {
    crops
        .iter()
        .map(|c| {
            format!(
                "<div class=\"crop-outline\" style=\"left:{}px;top:{}px;width:{}px;height:{}px\"></div>",
                c[0], c[1], c[2], c[3]
            )
        })
        .collect()
}

/// Every crop window, magnified x4-x8, for every panel (name, image id); the windows are where
/// FLIP against `reference` is highest.
pub(crate) fn crops(
    html: &mut String,
    reference: &str,
    crops: &[[u64; 4]],
    panels: &[(String, String)],
    w: u64,
    h: u64,
) {
    if crops.is_empty() {
        return;
    }
    let _ = writeln!(
        html,
        "<h3>Crops: the windows with the highest FLIP vs {} (outlined in the reference)</h3>",
        esc(reference)
    );
    for c in crops {
        let mag = (240 / c[2].max(1)).clamp(4, 8);
        let _ = writeln!(
            html,
            "<p class=\"muted\">x {} y {}, {}x{} pixels, x{mag}</p><div class=\"crops\">",
            c[0], c[1], c[2], c[3]
        );
        for (name, id) in panels {
            let _ = writeln!(
                html,
                "<div class=\"cropcell\"><div class=\"crop\" data-im=\"{id}\" style=\"width:{}px;height:{}px;background-size:{}px {}px;background-position:-{}px -{}px\"></div>{}</div>",
                c[2] * mag,
                c[3] * mag,
                w * mag,
                h * mag,
                c[0] * mag,
                c[1] * mag,
                esc(name)
            );
        }
        html.push_str("</div>\n");
    }
}
