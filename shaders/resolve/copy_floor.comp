#version 460
// The resolve's bandwidth floor (crates/cbr-render/src/resolve/mod.rs, CopyFloor): every input
// word read once, every output word written once, 16 bytes per access, nothing computed.
layout(local_size_x = LOCAL_SIZE_X) in;
layout(std430, set = 0, binding = BINDING_SRC) readonly buffer Src { uvec4 src[]; };
layout(std430, set = 0, binding = BINDING_DST) writeonly buffer Dst { uvec4 dst[]; };
PUSH_CONSTANTS  // words_in, words_out

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.words_out) return;
    uvec4 acc = uvec4(0u);
    for (uint k = i; k < pc.words_in; k += pc.words_out) acc ^= src[k];
    dst[i] = acc;
}
