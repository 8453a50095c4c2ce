// What taau's passes share (docs/upsampling.md; CPU reference:
// crates/cbr-render/src/techniques/taau/reference.rs): the push constants' meaning, the 3x3
// offsets and the kernels.
//
// sizes: W, H (output), w, h (render); jitter_ratio: the frame's jitter (render pixels), W / w,
// H / h; params: exposure scale, depth tolerance, gamma, the kernel's largest bias; accum: the
// history's weight cap still and moving, the speed (output pixels per frame) the moving cap is
// reached at, 1 / jitter phases (a lock's decay per frame); flags: x F_RESET.
PUSH_CONSTANTS

const ivec2 OFF[9] = ivec2[9](ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0), ivec2(0, 0),
                              ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));

const float PI = 3.14159265358979;

bool inside(ivec2 t, ivec2 size) { return all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, size)); }

// The kernel at squared distance x2 (already scaled): KERNEL 0 tent (radius 1), 1 Catmull-Rom,
// 2 Lanczos-2, sinc(x) sinc(x / 2). (FSR 2's polynomial approximation in x^2 saves the sines but
// is off by up to 0.049: on the moving demo it raised FLIP by 2.4%; docs/upsampling.md.)
float kernel_weight_sq(float x2) {
#if KERNEL == 0
    return max(1.0 - sqrt(x2), 0.0);
#elif KERNEL == 1
    float x = sqrt(x2);
    if (x < 1.0) return (1.5 * x - 2.5) * x2 + 1.0;
    if (x < 2.0) return ((-0.5 * x + 2.5) * x - 4.0) * x + 2.0;
    return 0.0;
#else
    if (x2 >= 4.0) return 0.0;
    if (x2 < 1e-8) return 1.0;
    float a = PI * sqrt(x2);
    return 2.0 * sin(a) * sin(0.5 * a) / (a * a);
#endif
}
