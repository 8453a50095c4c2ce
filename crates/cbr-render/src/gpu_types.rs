//! Host mirrors of shaders/inc/scene_types.glsl (one source of truth: the GLSL; the test below
//! compares these offsets with the compiled SPIR-V's).

use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameConstants {
    pub viewport: [f32; 4],
    pub output_size: [f32; 4],
    pub jitter: [f32; 4],
    pub ambient: [f32; 4],
    pub counts: [u32; 4],
    pub tangram: [i32; 4],
    pub screen_jitter: [f32; 4],
    pub pieces: [[i32; 4]; MAX_PIECES],
}

/// Tangram pieces the constants can hold (`pieces[8]` in scene_types.glsl).
pub const MAX_PIECES: usize = 8;

/// `counts.w` flags and `LAYOUT` values, as in scene_types.glsl.
pub const FLAG_PARITY: u32 = 1;
pub const FLAG_COUNT_SHADED: u32 = 2;
pub const FLAG_DEBUG_LOD: u32 = 8;

/// A material's texture paths (scene_types.glsl's MAT_*): the MAT_FEATURES define of a scene
/// pipeline compiles in only these, and a scene pass builds one pipeline per combination its
/// materials use.
pub const MAT_ALBEDO: u32 = 1;
pub const MAT_MASK: u32 = 2;
pub const MAT_BUMP: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ObjectData {
    pub clip_from_local: [f32; 16],
    pub prev_clip_from_local: [f32; 16],
    pub world_from_local: [f32; 16],
    pub normal_from_local: [f32; 16],
    pub ids: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialData {
    pub kd: [f32; 4],
    pub ks: [f32; 4],
    pub ke: [f32; 4],
    pub tex: [i32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightData {
    pub position: [f32; 4],
    pub color: [f32; 4],
}

/// A virtual point light of `deferred:vpls=N` (scene_types.glsl's `Vpl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vpl {
    /// xyz: camera-relative position; w: 1 where its RSM texel saw geometry, else 0 (dead).
    pub position: [f32; 4],
    /// xyz: unit normal, facing the sun.
    pub normal: [f32; 4],
    /// rgb: the flux it carries.
    pub flux: [f32; 4],
}

#[cfg(test)]
pub(crate) mod tests {
    use std::collections::HashMap;

    /// (struct name, member index) -> byte offset, read from SPIR-V decorations.
    pub fn member_offsets(words: &[u32]) -> HashMap<(String, u32), u32> {
        let mut names: HashMap<u32, String> = HashMap::new();
        let mut offsets: Vec<(u32, u32, u32)> = Vec::new();
        let mut i = 5;
        while i < words.len() {
            let (len, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
            let ops = &words[i + 1..i + len.max(1)];
            match op {
                5 => {
                    // OpName target "name"
                    let bytes: Vec<u8> = ops[1..]
                        .iter()
                        .flat_map(|w| w.to_le_bytes())
                        .take_while(|&b| b != 0)
                        .collect();
                    names.insert(ops[0], String::from_utf8_lossy(&bytes).into_owned());
                }
                72 if ops[2] == 35 => offsets.push((ops[0], ops[1], ops[3])), // OpMemberDecorate .. Offset
                _ => {}
            }
            i += len.max(1);
        }
        offsets
            .into_iter()
            .filter_map(|(ty, member, off)| names.get(&ty).map(|n| ((n.clone(), member), off)))
            .collect()
    }

    #[test]
    fn host_structs_match_the_shader_layout() {
        use std::mem::offset_of;
        let shaders = crate::shader_library();
        let defs = crate::scene_pass::shader_defines(crate::scene_pass::LAYOUT_ROTATED);
        let words = shaders
            .compile("scene/forward.frag", &defs)
            .expect("compiles");
        let off = member_offsets(&words);
        let check = |s: &str, m: u32, host: usize| {
            let dev = off.get(&(s.to_string(), m)).copied();
            assert_eq!(dev, Some(host as u32), "{s} member {m}");
        };
        use super::*;
        check("FrameConstants", 0, offset_of!(FrameConstants, viewport));
        check("FrameConstants", 1, offset_of!(FrameConstants, output_size));
        check("FrameConstants", 2, offset_of!(FrameConstants, jitter));
        check("FrameConstants", 3, offset_of!(FrameConstants, ambient));
        check("FrameConstants", 4, offset_of!(FrameConstants, counts));
        check("FrameConstants", 5, offset_of!(FrameConstants, tangram));
        check(
            "FrameConstants",
            6,
            offset_of!(FrameConstants, screen_jitter),
        );
        check("FrameConstants", 7, offset_of!(FrameConstants, pieces));
        check("ObjectData", 0, offset_of!(ObjectData, clip_from_local));
        check(
            "ObjectData",
            1,
            offset_of!(ObjectData, prev_clip_from_local),
        );
        check("ObjectData", 2, offset_of!(ObjectData, world_from_local));
        check("ObjectData", 3, offset_of!(ObjectData, normal_from_local));
        check("ObjectData", 4, offset_of!(ObjectData, ids));
        check("MaterialData", 0, offset_of!(MaterialData, kd));
        check("MaterialData", 1, offset_of!(MaterialData, ks));
        check("MaterialData", 2, offset_of!(MaterialData, ke));
        check("MaterialData", 3, offset_of!(MaterialData, tex));
        check("LightData", 0, offset_of!(LightData, position));
        check("LightData", 1, offset_of!(LightData, color));
    }

    #[test]
    fn the_vpl_struct_matches_the_shader_layout() {
        use std::mem::offset_of;
        let shaders = crate::shader_library();
        let defs = crate::techniques::deferred::lighting::shader_defines();
        let words = shaders
            .compile("deferred/lighting.comp", &defs)
            .expect("compiles");
        let off = member_offsets(&words);
        use super::Vpl;
        for (m, host) in [
            (0, offset_of!(Vpl, position)),
            (1, offset_of!(Vpl, normal)),
            (2, offset_of!(Vpl, flux)),
        ] {
            assert_eq!(off.get(&("Vpl".into(), m)).copied(), Some(host as u32));
        }
        assert_eq!(std::mem::size_of::<Vpl>(), 48);
    }
}
