// Display-space luma for FXAA: exposure, Narkowicz ACES fit, clamp, sRGB OETF, Rec. 601 weights.
float fxaa_display(float x, float exposure) {
    x = max(x * exposure, 0.0);
    float t = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return t <= 0.0031308 ? 12.92 * t : 1.055 * pow(t, 1.0 / 2.4) - 0.055;
}

float luma(vec3 c, float exposure) {
    return 0.299 * fxaa_display(c.r, exposure) + 0.587 * fxaa_display(c.g, exposure)
        + 0.114 * fxaa_display(c.b, exposure);
}
