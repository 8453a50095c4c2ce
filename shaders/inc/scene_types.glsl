// Host/shader shared structures of the scene pass. Mirrored by #[repr(C)] structs in
// crates/cbr-render/src/gpu_types.rs; a test compares their offsets with this file's SPIR-V.
#ifndef SCENE_TYPES_GLSL
#define SCENE_TYPES_GLSL

struct FrameConstants {
    vec4 viewport;      // width, height, 1/width, 1/height (pixels of the target being drawn)
    vec4 jitter;        // xy: sub-pixel offset in pixels added to the raster position; zw: 0
    vec4 ambient;       // rgb: ambient irradiance; w: texture LOD bias
    uvec4 counts;       // x: directional lights, y: point lights, z: frame index, w: flags
};

struct ObjectData {
    mat4 clip_from_local;       // this frame, unjittered, camera-relative
    mat4 prev_clip_from_local;  // previous frame (camera and object), for velocity
    mat4 world_from_local;      // camera-relative world: translation = object - camera position
    mat4 normal_from_local;     // inverse transpose of world_from_local's 3x3 (in a mat4)
    uvec4 ids;                  // x: object ID (index + 1; 0 = background), y: material, zw: 0
};

struct MaterialData {
    vec4 kd;    // rgb: diffuse albedo (multiplies the texture); w: 0
    vec4 ks;    // rgb: specular colour; w: Blinn-Phong exponent
    vec4 ke;    // rgb: emitted radiance; w: bump height scale (metres per unit height)
    ivec4 tex;  // x: albedo texture, y: alpha-mask texture, z: mask channel, w: bump texture (-1: none;
                //    the textures themselves are bound in the material's descriptor set)
};

struct LightData {
    vec4 position;  // xyz: camera-relative position (point) or travel direction (directional); w: 1 point, 0 directional
    vec4 color;     // rgb: colour * intensity; w: range (point lights; <= 0: no window)
};

#endif
