// Whether a 3x3 of reverse-Z depths (in OFF's order, row by row) is one plane: reverse-Z depth is
// affine in screen space on a plane, so on each of the four lines through the centre (k, 8 - k)
// d(-o) + d(o) - 2 d(0) is 0; one plane: within `tol` times d(0). A receding floor, whose depth
// span over three pixels can be large, is one. `+taa` and `taau.dilate` (CPU:
// cpu_math::depth_plane).
bool depth_plane(float d[9], float tol) {
    bool plane = true;
    for (int k = 0; k < 4; k++) plane = plane && abs(d[k] + d[8 - k] - 2.0 * d[4]) <= tol * d[4];
    return plane;
}
