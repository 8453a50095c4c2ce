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
    pub turning: [f32; 4],
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
/// Bits 8-12 of a MAT_FEATURES combination: the scene's `anisotropy` (scene_types.glsl's
/// MAT_ANISO), the same for every material with a texture; 0 where it is 1.
pub const MAT_ANISO_SHIFT: u32 = 8;

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

/// Lights (scene_types.glsl's UNIFORM_LIGHTS) a buffer of lights holds in its uniform part: its
/// first 64 KiB, which the shaders read as a uniform buffer; the lights past them come through a
/// storage buffer view of the rest of the same buffer ([`SplitBuffer`]).
pub const UNIFORM_LIGHTS: u64 = 2048;
/// VPLs (scene_types.glsl's UNIFORM_VPLS) a VPL buffer's uniform part holds: 65,280 bytes, a
/// multiple of 256 (the largest storage-buffer offset alignment Vulkan allows) under 64 KiB.
pub const UNIFORM_VPLS: u64 = 1360;

/// How a buffer of lights or VPLs is read: through two views, a uniform part of the first
/// `uniform` bytes (always whole, whatever the count) and a storage part of the rest of the
/// buffer (at least one element, so the view is never empty). The shaders read element i < the
/// uniform count from the first, the others from the second, in two loops split at that count:
/// llvmpipe (Mesa 22.3) loads a uniform buffer's element with an index the same in every lane
/// once per SIMD vector, and a storage buffer's lane by lane, each lane's load a few tens of
/// instructions; GPUs read both through their scalar or constant caches
/// (docs/interleaved.md, "Issue 57: the lights in uniform buffers").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitBuffer {
    /// Bytes of the uniform part (the storage part's offset).
    pub uniform: u64,
    /// Bytes of one element.
    pub element: u64,
}

impl SplitBuffer {
    /// Lights: [`UNIFORM_LIGHTS`] in the uniform part.
    pub const LIGHTS: SplitBuffer = SplitBuffer::of(UNIFORM_LIGHTS, size_of::<LightData>() as u64);
    /// VPLs: [`UNIFORM_VPLS`] in the uniform part.
    pub const VPLS: SplitBuffer = SplitBuffer::of(UNIFORM_VPLS, size_of::<Vpl>() as u64);

    pub const fn of(uniform: u64, element: u64) -> SplitBuffer {
        SplitBuffer {
            uniform: uniform * element,
            element,
        }
    }

    /// Bytes of a buffer of `count` elements: the uniform part whole and at least one element
    /// past it.
    pub fn bytes(self, count: u64) -> u64 {
        (count * self.element).max(self.uniform + self.element)
    }

    /// Binds `buffer` (made [`SplitBuffer::bytes`] long) as `uniform` (its first part) and
    /// `storage` (the rest).
    pub fn bind<'a>(
        self,
        binds: crate::pass::Binds<'a>,
        buffer: &'a cbr_gpu::Buffer,
        uniform: &'static str,
        storage: &'static str,
    ) -> crate::pass::Binds<'a> {
        let rest = buffer.size().saturating_sub(self.uniform);
        binds
            .buffer_part(uniform, buffer, 0, self.uniform)
            .buffer_part(storage, buffer, self.uniform, rest)
    }

    /// Refuses a device that cannot bind the uniform part or align the storage part.
    pub fn check(self, caps: &cbr_gpu::Caps, device: &str, what: &str) -> cbr_gpu::Result<()> {
        if self.uniform > u64::from(caps.max_uniform_buffer_range) {
            return Err(cbr_gpu::GpuError::Other(format!(
                "{device}: {what} keep their first {} bytes in a uniform buffer, and this device \
                 binds at most {} bytes as one (maxUniformBufferRange; lavapipe and desktop GPUs \
                 allow 64 KiB)",
                self.uniform, caps.max_uniform_buffer_range
            )));
        }
        let align = caps.min_storage_buffer_offset_alignment.max(1);
        if !self.uniform.is_multiple_of(align) {
            return Err(cbr_gpu::GpuError::Other(format!(
                "{device}: {what} past the uniform part start at byte {}, not a multiple of \
                 this device's minStorageBufferOffsetAlignment ({align})",
                self.uniform
            )));
        }
        Ok(())
    }
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

    /// Each instruction of a SPIR-V module: its opcode and operands.
    fn instructions(words: &[u32]) -> Vec<(u32, &[u32])> {
        let mut out = Vec::new();
        let mut i = 5;
        while i < words.len() {
            let (len, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
            out.push((op, &words[i + 1..i + len.max(1)]));
            i += len.max(1);
        }
        out
    }

    /// Id -> name, from the module's OpName instructions.
    fn names(words: &[u32]) -> HashMap<u32, String> {
        instructions(words)
            .into_iter()
            .filter(|(op, _)| *op == 5) // OpName target "name"
            .map(|(_, ops)| {
                let bytes: Vec<u8> = ops[1..]
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .take_while(|&b| b != 0)
                    .collect();
                (ops[0], String::from_utf8_lossy(&bytes).into_owned())
            })
            .collect()
    }

    /// (struct name, member index) -> byte offset, read from SPIR-V decorations.
    pub fn member_offsets(words: &[u32]) -> HashMap<(String, u32), u32> {
        let names = names(words);
        instructions(words)
            .into_iter()
            // OpMemberDecorate struct member Offset value
            .filter(|(op, ops)| *op == 72 && ops[2] == 35)
            .filter_map(|(_, ops)| names.get(&ops[0]).map(|n| ((n.clone(), ops[1]), ops[3])))
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
        check("FrameConstants", 7, offset_of!(FrameConstants, turning));
        check("FrameConstants", 8, offset_of!(FrameConstants, pieces));
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

    /// Struct name -> the lengths of the fixed-size arrays of it (OpTypeArray) in `words`.
    fn array_lengths(words: &[u32]) -> HashMap<String, Vec<u32>> {
        let names = names(words);
        let code = instructions(words);
        // OpConstant type result value
        let consts: HashMap<u32, u32> = code
            .iter()
            .filter(|(op, _)| *op == 43)
            .map(|(_, ops)| (ops[1], ops[2]))
            .collect();
        let mut out: HashMap<String, Vec<u32>> = HashMap::new();
        // OpTypeArray result element length
        for (_, ops) in code.iter().filter(|(op, _)| *op == 28) {
            if let (Some(n), Some(&l)) = (names.get(&ops[1]), consts.get(&ops[2])) {
                out.entry(n.clone()).or_default().push(l);
            }
        }
        out
    }

    /// The uniform parts the host binds are the arrays the shaders declare (light_buffers.glsl),
    /// and they fit the 64 KiB every desktop device binds; the storage parts start 256-aligned.
    #[test]
    fn the_uniform_parts_match_the_shaders() {
        use super::*;
        let shaders = crate::shader_library();
        let defs = crate::techniques::deferred::lighting::shader_defines();
        let words = shaders
            .compile("deferred/lighting.comp", &defs)
            .expect("compiles");
        let lengths = array_lengths(&words);
        let light = lengths.get("LightData").cloned().unwrap_or_default();
        let vpl = lengths.get("Vpl").cloned().unwrap_or_default();
        // The scene's lights and the extra point lights; the VPLs.
        assert_eq!(light, vec![UNIFORM_LIGHTS as u32; 2], "{lengths:?}");
        assert_eq!(vpl, vec![UNIFORM_VPLS as u32], "{lengths:?}");
        for split in [SplitBuffer::LIGHTS, SplitBuffer::VPLS] {
            assert!(
                split.uniform <= 1 << 16 && split.uniform % 256 == 0,
                "{split:?}"
            );
        }
        assert_eq!(SplitBuffer::LIGHTS.bytes(0), 2049 * 32);
        assert_eq!(SplitBuffer::LIGHTS.bytes(3000), 3000 * 32);
        assert_eq!(SplitBuffer::VPLS.uniform, 65280);
        // A device that binds less, or aligns coarser, is refused by name.
        let caps = |range, align| cbr_gpu::Caps {
            max_uniform_buffer_range: range,
            min_storage_buffer_offset_alignment: align,
            ..cbr_gpu::Caps::default()
        };
        let lights = SplitBuffer::LIGHTS;
        assert!(lights.check(&caps(1 << 16, 256), "dev", "lights").is_ok());
        let err = lights
            .check(&caps(16384, 16), "dev", "lights")
            .unwrap_err()
            .to_string();
        assert!(err.contains("dev") && err.contains("16384"), "{err}");
        let odd = SplitBuffer::of(1365, 48);
        let err = odd
            .check(&caps(1 << 16, 256), "dev", "VPLs")
            .unwrap_err()
            .to_string();
        assert!(err.contains("minStorageBufferOffsetAlignment"), "{err}");
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
