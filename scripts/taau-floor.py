#!/usr/bin/env python3
"""The floor of FSR 2's algorithm on lavapipe: `taau`'s passes against `native`'s frame with the
accumulation pass stripped down (docs/upsampling.md, "The floor of FSR 2's passes on lavapipe").

    scripts/taau-floor.py [--cbr BIN] [--runs 2] [--width 1280 --height 720] [--frames 5] [-o DIR]

Writes two variants of shaders/ into DIR (through CBR_SHADER_DIR, the same binary; nothing in the
repository changes) whose `taau/accumulate.comp` keeps its declarations and replaces `main`:

- `skeleton`: no accumulation at all: one prepared texel read and FSR 2's three stores (the
  history's colour and weight, its aux, the output), no full-resolution geometry;
- `minimal`: the least of FSR 2's step: the dilated velocity, the 3x3 render samples weighted by
  the Lanczos-2 kernel and the rectification box's moments, one history texel (nearest), the
  clip and the blend, the same three stores.

Each run times `native,taau` (`cbr bench builtin:demo --timing-only`) with the shipped shaders
and each variant, in turn, and prints every pass's median and the sums against `native`'s frame
of the same run. The other passes (dilate, depth clip, lock, RCAS) are the shipped ones in every
variant. The variants are measurements only: they are not `taau` and their images are not used.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SKELETON = """void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 out_size = pc.sizes.xy, size = pc.sizes.zw;
    if (!inside(p, out_size)) return;
    vec2 src = (vec2(p) + 0.5) / pc.jitter_ratio.zw;
    vec4 pre = texelFetch(prepared, clamp(ivec2(floor(src)), ivec2(0), size - 1), 0);
    imageStore(out_hist, p, vec4(pre.xyz, 1.0));
    imageStore(out_aux, p, vec4(0.0, pre.x, 0.0, 0.0));
    imageStore(accumulated, p, vec4(linear_from_perceptual(pre.xyz, pc.params.x), 1.0));
}
"""

MINIMAL = """void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 out_size = pc.sizes.xy, size = pc.sizes.zw;
    if (!inside(p, out_size)) return;
    vec2 ratio = pc.jitter_ratio.zw, jit = pc.jitter_ratio.xy;
    vec2 src = (vec2(p) + 0.5) / ratio;
    vec2 v = texelFetch(dilated, clamp(ivec2(floor(src)), ivec2(0), size - 1), 0).xy * ratio;
    ivec2 c0 = clamp(ivec2(floor(src + jit)), ivec2(0), size - 1);
    vec3 acc = vec3(0.0), m1 = vec3(0.0), m2 = vec3(0.0);
    float wsum = 0.0, count = 0.0;
    for (int k = 0; k < 9; k++) {
        ivec2 t = clamp(c0 + OFF[k], ivec2(0), size - 1);
        vec3 y = texelFetch(prepared, t, 0).xyz;
        vec2 d = vec2(t) + 0.5 - jit - src;
        float w = kernel_weight_sq(dot(d, d));
        acc += w * y;
        wsum += w;
        float b = exp(-BOX_CURVE * dot(d, d));
        m1 += b * y;
        m2 += b * y * y;
        count += b;
    }
    vec3 cur = acc / max(wsum, 1e-4);
    vec4 ht = hist_texel(ivec2(floor(vec2(p) + 0.5 - v)));
    vec3 mu = m1 / count;
    vec3 sigma = sqrt(max(m2 / count - mu * mu, vec3(0.0)));
    vec3 h = clip_towards(mu, ht.rgb, mu - pc.params.z * sigma, mu + pc.params.z * sigma);
    float hk = min(ht.w, pc.accum.x);
    vec3 result = (hk * h + cur) / (hk + 1.0);
    imageStore(out_hist, p, vec4(result, hk + 1.0));
    imageStore(out_aux, p, vec4(0.0, cur.x, 0.0, 0.0));
    imageStore(accumulated, p, vec4(linear_from_perceptual(result, pc.params.x), 1.0));
}
"""


def variant(out, name, main):
    """shaders/ copied to out/name with accumulate.comp's main replaced."""
    d = os.path.join(out, name)
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(os.path.join(ROOT, "shaders"), d)
    path = os.path.join(d, "taau", "accumulate.comp")
    src = open(path).read()
    i = src.index("void main() {")
    open(path, "w").write(src[:i] + main)
    return d


def run(args, name, shaders):
    out = os.path.join(args.out, "runs", name)
    env = dict(os.environ)
    if shaders:
        env["CBR_SHADER_DIR"] = shaders
    cmd = [args.cbr, "bench", "builtin:demo", "--width", str(args.width), "--height",
           str(args.height), "--timing-only", "--techniques", "native,taau", "--warmup", "2",
           "--frames", str(args.frames), "-o", out]
    r = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"taau-floor: `{' '.join(cmd)}` failed:\n{r.stderr[-2000:]}")
    rows = {row["config"]: row for row in json.load(open(os.path.join(out, "bench.json")))["rows"]}
    native = rows["native"]["frame_ms"]["median"]
    passes = {k.split(".", 1)[1]: v["median"] for k, v in rows["taau"]["passes"].items()
              if k.startswith("taau.") and k != "taau.raster"}
    return native, passes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cbr", default=os.path.join(ROOT, "target/release/cbr"))
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "taau-floor"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    variants = [("shipped", None), ("skeleton", variant(args.out, "skeleton", SKELETON)),
                ("minimal", variant(args.out, "minimal", MINIMAL))]
    print(f"cbr bench builtin:demo --width {args.width} --height {args.height} --timing-only "
          f"--techniques native,taau --warmup 2 --frames {args.frames}; medians, ms")
    print("| run | accumulation | `native` frame | accumulate | dilate | depth clip | lock | rcas "
          "| all passes / `native` | accumulate + rcas / `native` |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    results = []
    for k in range(args.runs):
        for name, shaders in variants:
            native, p = run(args, f"{name}-{k + 1}", shaders)
            total = sum(p.values())
            results.append({"run": k + 1, "variant": name, "native_ms": native, "passes": p})
            print(f"| {k + 1} | {name} | {native:.1f} | {p['accumulate']:.1f} | {p['dilate']:.1f} "
                  f"| {p['depth_clip']:.1f} | {p['lock']:.1f} | {p['rcas']:.1f} "
                  f"| {total / native:.3f} | {(p['accumulate'] + p['rcas']) / native:.3f} |",
                  flush=True)
    json.dump(results, open(os.path.join(args.out, "floor.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
