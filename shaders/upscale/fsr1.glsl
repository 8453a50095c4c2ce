// FSR 1's colour encoding, shared by easu.comp and rcas.comp (CPU reference:
// crates/cbr-render/src/techniques/upscale/reference.rs). FSR 1 expects perceptual colour in
// [0, 1]; cbr's frames are linear HDR. Encode: exposure-scaled, negatives to 0, the reversible
// tonemap c / (1 + max(r, g, b)) (every channel below 1, RCAS's peak), then a square root (gamma
// 2). Decode inverts it; both passes read and write linear HDR and encode internally.

const float DECODE_FLOOR = 1.0 / 4096.0;  // the smallest 1 - max(t) decode divides by

float fsr_max3(vec3 c) { return max(c.r, max(c.g, c.b)); }

vec3 fsr_encode(vec3 c, float exposure) {
    vec3 e = max(c * exposure, vec3(0.0));
    float d = 1.0 + fsr_max3(e);
    return sqrt(e / d);
}

vec3 fsr_decode(vec3 g, float exposure) {
    vec3 t = g * g;
    float d = max(1.0 - fsr_max3(t), DECODE_FLOOR) * exposure;
    return t / d;
}

// FSR's luma: r/2 + g + b/2.
float fsr_luma(vec3 c) { return 0.5 * c.r + c.g + 0.5 * c.b; }
