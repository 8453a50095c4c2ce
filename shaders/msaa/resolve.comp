#version 460
// `msaa:N`: resolves the multisampled colour to one value per pixel, and takes velocity from
// sample 0. Box: the mean of the N samples. HDR-safe (HDR_SAFE=1): the mean in a tonemapped
// space, T(c) = c / (1 + L(c)), inverted after, T^-1(c) = c / (1 - L(c)), with L the Rec. 709
// luminance; bright samples then no longer dominate edge pixels (Karis 2013). CPU reference:
// crates/cbr-render/src/techniques/msaa.rs (`resolve_reference`).
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform sampler2DMS color;
layout(set = 0, binding = BINDING_VELOCITY) uniform sampler2DMS velocity;
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_VELOCITY, rg32f) uniform writeonly image2D out_velocity;
PUSH_CONSTANTS  // size_samples: W, H, N, 0

float luma(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size_samples.xy))) return;
    int n = pc.size_samples.z;
    vec4 sum = vec4(0.0);
    for (int s = 0; s < n; s++) {
        vec4 c = texelFetch(color, p, s);
#if HDR_SAFE
        c.rgb /= 1.0 + max(luma(c.rgb), 0.0);
#endif
        sum += c;
    }
    vec4 avg = sum / float(n);
#if HDR_SAFE
    avg.rgb /= max(1.0 - luma(avg.rgb), 1e-6);
#endif
    imageStore(out_color, p, avg);
    imageStore(out_velocity, p, vec4(texelFetch(velocity, p, 0).xy, 0.0, 0.0));
}
