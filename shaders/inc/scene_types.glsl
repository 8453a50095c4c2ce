// Host/shader shared structures of the scene passes. Mirrored by #[repr(C)] structs in
// crates/cbr-render/src/gpu_types.rs; a test compares their offsets with this file's SPIR-V.
#ifndef SCENE_TYPES_GLSL
#define SCENE_TYPES_GLSL

// Raster layouts (the LAYOUT define of the scene shaders; crates/cbr-render/src/layouts.rs).
#define LAYOUT_NATIVE 0
#define LAYOUT_MASKED 1
#define LAYOUT_SPLIT 2
#define LAYOUT_ROTATED 3
#define LAYOUT_MSAA2X 4
#define LAYOUT_INTERLACED 5  // `interlaced`: full resolution, the rows of the other parity demoted

// counts.w flags
#define FLAG_PARITY 1u          // the frame's parity: checkerboard (x + y) mod 2, interlaced y mod 2
#define FLAG_COUNT_SHADED 2u    // count shaded (non-helper) fragments in the counter buffer
// 4u: free (was the LOD-gradients flag, now the LOD_GRADIENTS define of the scene pass)
#define FLAG_DEBUG_LOD 8u       // write the albedo lookup's level of detail to colour.r

// A material's texture paths (gpu_types.rs MAT_*). MAT_FEATURES, a define of the scene raster's
// pipelines, compiles in only the paths of the materials drawn with it (scene_pass.rs builds one
// pipeline per combination the scene uses): llvmpipe runs the body of every branch for every
// fragment, even when no fragment of the draw takes it. Without the define, every path.
#define MAT_ALBEDO 1
#define MAT_MASK 2
#define MAT_BUMP 4
// Bits 8-12: the scene's `anisotropy` (at most that many lookups along a texture footprint's
// longer side: inc/aniso.glsl), the same for every material; 0 or 1: one isotropic trilinear
// lookup, the sampler's own filter.
#define MAT_ANISO_SHIFT 8
#ifndef MAT_FEATURES
#define MAT_FEATURES 7
#endif
#define MAT_ANISO ((MAT_FEATURES >> MAT_ANISO_SHIFT) & 31)

struct FrameConstants {
    vec4 viewport;      // the viewport NDC maps to, in target pixels: width, height, 1/width, 1/height
    vec4 output_size;   // full-resolution W, H, 1/W, 1/H (velocity is in these pixels)
    vec4 jitter;        // sub-pixel raster offsets in target pixels: xy layer/instance 0, zw layer 1
    vec4 ambient;       // rgb: ambient irradiance; w: texture LOD bias
    uvec4 counts;       // x: directional lights, y: point lights, z: frame index, w: flags
    ivec4 tangram;      // x: side L, y: number of pieces
    vec4 screen_jitter; // xy: sub-pixel offset of the projection in output pixels, every layout
                        // (+x right, +y down moves the geometry: `--jitter`, `+taa`); z: the
                        // LOD bias a moving fragment sheds, w: 1 / the speed (pixels per frame)
                        // at which it sheds all of it (0: none)
    vec4 turning;       // x: the LOD bias a turning object's fragment withdraws in proportion to
                        // its turn (ObjectData.ids.z: a temporal technique's sharper bias, which
                        // its history cannot average where the object's own rotation changes its
                        // shading every frame); yzw: 0
    ivec4 pieces[8];    // xy: the (m, n) translation of each tangram piece, in units of L
};

struct ObjectData {
    mat4 clip_from_local;       // this frame, unjittered, camera-relative
    mat4 prev_clip_from_local;  // previous frame (camera and object), for velocity
    mat4 world_from_local;      // camera-relative world: translation = object - camera position
    mat4 normal_from_local;     // inverse transpose of world_from_local's 3x3 (in a mat4)
    uvec4 ids;                  // x: object ID (index + 1; 0 = background), y: material,
                                // z: the object's turn (f32 bits: its own rotation this frame
                                // over TURN_FULL, at most 1; gpu_scene.rs), w: 0
};

struct MaterialData {
    vec4 kd;    // rgb: diffuse albedo (multiplies the texture); w: 0
    vec4 ks;    // rgb: specular colour; w: Blinn-Phong exponent
    vec4 ke;    // rgb: emitted radiance; w: bump height scale (metres per unit height)
    ivec4 tex;  // x: albedo texture, y: alpha-mask texture, z: mask channel, w: bump texture (-1: none;
                //    the textures themselves are bound in the material's descriptor set)
};

// Lights and VPLs a light buffer holds in its uniform part (inc/light_buffers.glsl; gpu_types.rs
// UNIFORM_LIGHTS, UNIFORM_VPLS): 64 KiB of lights, and 65,280 bytes of VPLs (a multiple of 256,
// the largest storage-buffer offset alignment Vulkan allows, where the rest's view starts).
#define UNIFORM_LIGHTS 2048u
#define UNIFORM_VPLS 1360u

struct LightData {
    vec4 position;  // xyz: camera-relative position (point) or travel direction (directional); w: 1 point, 0 directional
    vec4 color;     // rgb: colour * intensity; w: range (point lights; <= 0: no window)
};

// A virtual point light (`deferred:vpls=N`): a reflective-shadow-map texel that reflects the sun.
struct Vpl {
    vec4 position;  // xyz: camera-relative position; w: 1 where the RSM texel saw geometry, else 0
    vec4 normal;    // xyz: unit normal, facing the sun; w: 0
    vec4 flux;      // rgb: reflected flux this VPL carries (its share of the RSM); w: 0
};

#endif
