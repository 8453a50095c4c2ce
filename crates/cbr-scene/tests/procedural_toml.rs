//! A scene TOML naming a procedural scene keeps that scene's camera path when it sets the
//! resolution (only an OBJ's automatic framing is redone for a new aspect), and `textures = false`
//! drops every material's textures.

use cbr_scene::{AlphaSource, LoadOptions, builtin, load};

fn load_toml(text: &str) -> cbr_scene::Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, text).unwrap();
    load(&path.to_string_lossy(), &LoadOptions::default()).unwrap()
}

#[test]
fn a_procedural_scene_keeps_its_camera_at_another_resolution() {
    let demo = builtin("demo").unwrap();
    let s = load_toml("procedural = \"demo\"\nwidth = 320\nheight = 180\n");
    assert_eq!((s.settings.width, s.settings.height), (320, 180));
    assert_eq!(s.camera.keys.len(), demo.camera.keys.len());
    for (a, b) in s.camera.keys.iter().zip(&demo.camera.keys) {
        assert_eq!(a.position, b.position);
        assert_eq!(a.target, b.target);
    }
}

#[test]
fn textures_false_drops_every_texture() {
    let demo = builtin("demo").unwrap();
    assert!(demo.materials.iter().any(|m| m.kd_tex.is_some()));
    assert!(
        demo.materials
            .iter()
            .any(|m| m.alpha != AlphaSource::Opaque)
    );
    let s = load_toml("procedural = \"demo\"\ntextures = false\n");
    assert!(
        s.materials
            .iter()
            .all(|m| m.kd_tex.is_none() && m.bump_tex.is_none() && m.alpha == AlphaSource::Opaque)
    );
}
