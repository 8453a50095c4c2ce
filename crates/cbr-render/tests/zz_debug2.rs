mod common;
use cbr_render::{RenderSettings, Renderer, Spec};
#[test]
fn sib() {
    let gpu = common::gpu();
    let mut s = cbr_scene::load(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/sibenik.toml"),
        &Default::default(),
    )
    .unwrap();
    (s.settings.width, s.settings.height) = (160, 90);
    let shaders = cbr_render::shader_library();
    for spec in ["analytic", "native"] {
        let mut r = Renderer::new(
            &gpu,
            &shaders,
            &s,
            RenderSettings::new(160, 90, Spec::parse(spec).unwrap()),
        )
        .unwrap();
        let out = r.render(&s, 0).unwrap();
        for (x, y) in [(80usize, 80usize), (60, 85), (20, 60), (80, 30)] {
            let i = y * 160 + x;
            let c: Vec<f32> = out.color[i * 4..i * 4 + 3]
                .iter()
                .map(|h| h.to_f32())
                .collect();
            let a = out.analytic.as_ref();
            println!(
                "{spec} ({x},{y}) c {c:?} ids {:?} d {} cov {:?} frags {:?} vis {:?} over {:?}",
                out.ids[i],
                out.depth[i],
                out.coverage.as_ref().map(|c| c.fraction[i]),
                a.map(|a| a.fragments[i]),
                a.map(|a| a.visible[i]),
                a.map(|a| a.overflow[i])
            );
        }
        println!("{spec} objects {}", s.objects.len());
    }
}
