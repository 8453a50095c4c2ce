// The scene's lights, the extra point lights (`points=N`) and the VPLs (`vpls=N`) of a pass,
// each one buffer seen through two views (crates/cbr-render/src/gpu_types.rs, SplitBuffer): its
// first UNIFORM_LIGHTS lights (UNIFORM_VPLS VPLs) as a uniform buffer, the rest as a storage
// buffer (`more_*`). Declared where the pass binds them (their BINDING_* defines), in set
// LIGHTS_SET (0 unless defined before the include).
//
// Why: every loop reads them with an index the same in every lane, and llvmpipe (Mesa 22.3)
// loads a uniform buffer's element once per SIMD vector but a storage buffer's lane by lane (a
// point light's 32 bytes cost about 580 instructions per 8-lane vector that way: docs/
// interleaved.md, "Issue 57: the lights in uniform buffers"); GPUs read either through their
// scalar or constant caches. A loop over them runs as two loops, the uniform part's and then
// the rest's (never one loop with an if: SIMD hardware that runs both sides of a branch, as
// llvmpipe does, would then load from both).
#ifndef LIGHT_BUFFERS_GLSL
#define LIGHT_BUFFERS_GLSL
#include "scene_types.glsl"
#ifndef LIGHTS_SET
#define LIGHTS_SET 0
#endif
#ifdef BINDING_LIGHTS
layout(std140, set = LIGHTS_SET, binding = BINDING_LIGHTS) uniform Lights { LightData lights[UNIFORM_LIGHTS]; };
layout(std430, set = LIGHTS_SET, binding = BINDING_MORE_LIGHTS) readonly buffer MoreLights { LightData more_lights[]; };
#endif
#ifdef BINDING_POINTS
layout(std140, set = LIGHTS_SET, binding = BINDING_POINTS) uniform Points { LightData points[UNIFORM_LIGHTS]; };
layout(std430, set = LIGHTS_SET, binding = BINDING_MORE_POINTS) readonly buffer MorePoints { LightData more_points[]; };
#endif
#ifdef BINDING_VPLS
layout(std140, set = LIGHTS_SET, binding = BINDING_VPLS) uniform Vpls { Vpl vpls[UNIFORM_VPLS]; };
layout(std430, set = LIGHTS_SET, binding = BINDING_MORE_VPLS) readonly buffer MoreVpls { Vpl more_vpls[]; };
#endif
#endif
