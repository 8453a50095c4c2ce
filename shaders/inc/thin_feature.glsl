// A thin feature (FSR 2's lock test; `+taa`'s locks and `taau.lock`; CPU:
// cpu_math::thin_feature): l, a 3x3 of perceptual lumas in OFF's order, whose centre is a ridge,
// above or below every neighbour not similar to it (similar: a ratio under 1.05), with no 2x2
// quad around the centre all similar to it.
bool similar_luma(float a, float b) {
    float lo = min(a, b), hi = max(a, b);
    return hi <= 0.0 || (lo > 0.0 && hi < 1.05 * lo);
}
bool thin_feature(float l[9]) {
    float n = l[4];
    bool sim[9];
    float lo = 1e30, hi = -1e30;
    for (int k = 0; k < 9; k++) {
        sim[k] = k == 4 || similar_luma(l[k], n);
        if (!sim[k]) {
            lo = min(lo, l[k]);
            hi = max(hi, l[k]);
        }
    }
    if (!(n > hi || n < lo)) return false;
    // The four 2x2 quads holding the centre (3x3 indices).
    return !((sim[0] && sim[1] && sim[3]) || (sim[1] && sim[2] && sim[5]) ||
             (sim[3] && sim[6] && sim[7]) || (sim[5] && sim[7] && sim[8]));
}
