// What taau's passes share (docs/upsampling.md; CPU reference:
// crates/cbr-render/src/techniques/taau/reference.rs): the push constants' meaning and the 3x3
// offsets.
//
// sizes: W, H (output), w, h (render); jitter_ratio: the frame's jitter (render pixels), W / w,
// H / h; params: exposure scale, depth tolerance, gamma, the kernel's largest bias; accum: the
// history's weight cap still and moving, the speed (output pixels per frame) the moving cap is
// reached at, 1 / jitter phases (a lock's decay per frame); flags: x F_RESET.
PUSH_CONSTANTS

const ivec2 OFF[9] = ivec2[9](ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0), ivec2(0, 0),
                              ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));

bool inside(ivec2 t, ivec2 size) { return all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, size)); }
