#version 460
// `+sharpen`: out = max(c + a (4 c - n - s - e - w), 0) per channel, edges clamped, alpha 1.
// CPU reference: crates/cbr-render/src/post/sharpen.rs.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_SRC) uniform sampler2D src;
layout(set = 0, binding = BINDING_OUT, rgba16f) uniform writeonly image2D dst;
PUSH_CONSTANTS  // size_amount: W, H, amount, 0

vec3 at(ivec2 p) {
    ivec2 size = ivec2(pc.size_amount.xy);
    return texelFetch(src, clamp(p, ivec2(0), size - 1), 0).rgb;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(pc.size_amount.xy)))) return;
    vec3 m = at(p);
    vec3 n = at(p + ivec2(0, -1)) + at(p + ivec2(0, 1)) + at(p + ivec2(-1, 0)) + at(p + ivec2(1, 0));
    vec3 o = max(m + pc.size_amount.z * (4.0 * m - n), vec3(0.0));
    imageStore(dst, p, vec4(o, 1.0));
}
