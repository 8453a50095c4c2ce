// Lanczos-3, 3 sin(pi x) sin(pi x / 3) / (pi x)^2, at a resampling's 6 taps per axis, distances
// x = j - f (j = -2..3, f in [0, 1)), from three sines: sin(pi (j - f)) = -(-1)^j sin(pi f) and
// sin(pi (j - f) / 3) = sin(pi j / 3) cos(pi f / 3) - cos(pi j / 3) sin(pi f / 3) (cpu_math's
// `lanczos3_weights`). At f = 0 the weights are exactly 1 at j = 0 and 0 elsewhere. Every
// reprojection resamples a history, and its blur compounds over the frames the history holds:
// Lanczos-3 keeps more detail than Lanczos-2 or Catmull-Rom (`taau`'s history and `+taa`'s;
// docs/upsampling.md, docs/post-aa.md).
void lanczos3_weights(float f, out float w[6]) {
    const float PI = 3.14159265358979;
    const float S3 = 0.866025403784439;
    const float SJ[6] = float[6](-S3, -S3, 0.0, S3, S3, 0.0);
    const float CJ[6] = float[6](-0.5, 0.5, 1.0, 0.5, -0.5, -1.0);
    // sin(pi f) = sin(pi (1 - f)): the smaller argument keeps its precision near f = 1.
    float s = sin(PI * min(f, 1.0 - f)), s3 = sin(PI * f / 3.0), c3 = cos(PI * f / 3.0);
    for (int k = 0; k < 6; k++) {
        float x = float(k - 2) - f;
        float a = PI * x;
        float sx = (k & 1) == 0 ? -s : s;
        w[k] = abs(x) < 1e-4 ? 1.0 : 3.0 * sx * (SJ[k] * c3 - CJ[k] * s3) / (a * a);
    }
}
