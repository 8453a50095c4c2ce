#!/usr/bin/env python3
"""Oracle values for cbr-metrics: NVIDIA's flip-evaluator and scikit-image on image pairs made from
exactly reproducible formulas (integer hashes, shifts, box blurs, exponential ramps), which
crates/cbr-metrics/tests/oracles.rs regenerates bit for bit (f64 arithmetic, then float32).

    python3 -m pip install flip-evaluator==1.7 scikit-image==0.26.0 numpy
    python3 references/oracles/make_oracles.py > references/oracles/oracles.json

Definitions used on the oracle maps: weighted percentile q = the smallest error e whose errors <= e
sum to at least q of the total (FLIP's pooling); SSIM per RGB channel averaged (channel_axis=-1);
PSNR over all channels with data_range 1. HDR pairs are compared for SSIM/PSNR through cbr's display
transform (ACES Narkowicz fit, sRGB OETF), written out below.
"""
import json
import sys
from importlib.metadata import version

import flip_evaluator as flip
import numpy as np
import skimage
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

W, H = 128, 96


def hash01(salt):
    """Per-element integer hash in [0, 1): ((i * 2654435761 + salt * 40503) mod 2^32) / 2^32."""
    i = np.arange(H * W * 3, dtype=np.uint64).reshape(H, W, 3)
    h = (i * np.uint64(2654435761) + np.uint64(salt * 40503)) % np.uint64(2**32)
    return h.astype(np.float64) / 2.0**32


def base():
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    r = ((x * 3 + y * 5) % 17) / 16.0
    g = x / (W - 1)
    b = (np.floor(x / 8) + np.floor(y / 8)) % 2 * 0.6 + 0.2
    return np.stack([r, g, b], -1)


def shift(img, dx):
    """out[y, x] = img[y, clamp(x - dx)]"""
    xs = np.clip(np.arange(W) - dx, 0, W - 1)
    return img[:, xs, :]


def box3(img):
    """3x3 box blur with clamped borders."""
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    acc = np.zeros_like(img)
    for dy in range(3):
        for dx in range(3):
            acc += p[dy:dy + H, dx:dx + W, :]
    return acc / 9.0


def hdr_base():
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    ramp = np.exp2(x / (W - 1) * 12.0 - 6.0)
    return np.stack([ramp, ramp * (0.5 + 0.5 * (y / (H - 1))), ramp * ((x + y) % 7) / 6.0], -1)


def pairs():
    b = base()
    yield "noise_small", b, np.clip(b + (hash01(1) - 0.5) * 0.05, 0, 1), False
    yield "noise_large", b, np.clip(b + (hash01(2) - 0.5) * 0.3, 0, 1), False
    yield "blur", b, box3(b), False
    yield "shift", b, shift(b, 1), False
    hb = hdr_base()
    yield "hdr_noise", hb, hb * (1.0 + (hash01(3) - 0.5) * 0.2), True
    yield "hdr_shift", hb, shift(hb, 2), True
    hi = hb * 50.0 * (hash01(4) > 0.97) + hb
    yield "hdr_highlights", hi, box3(hi), True


def display(x):
    x = np.maximum(x, 0.0)
    t = np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    return np.where(t <= 0.0031308, 12.92 * t, 1.055 * np.power(t, 1 / 2.4) - 0.055)


def weighted(values, q):
    v = np.sort(values.astype(np.float64).reshape(-1))
    c = np.cumsum(v)
    return float(v[np.searchsorted(c, q * c[-1])])


def main():
    out = {"size": [W, H], "versions": {"flip-evaluator": version("flip-evaluator"), "scikit-image": skimage.__version__, "numpy": np.__version__, "python": sys.version.split()[0]}, "pairs": {}}
    for name, ref, test, hdr in pairs():
        ref32, test32 = ref.astype(np.float32), test.astype(np.float32)
        entry = {"hdr": hdr}
        if hdr:
            m, mean, params = flip.evaluate(ref32, test32, "HDR", applyMagma=False)
            entry["hdrflip"] = {"mean": float(mean), "start_exposure": params["startExposure"], "stop_exposure": params["stopExposure"], "exposures": params["numExposures"]}
            dr, dt = display(ref32.astype(np.float64)), display(test32.astype(np.float64))
        else:
            dr, dt = ref32.astype(np.float64), test32.astype(np.float64)
        m, mean, _ = flip.evaluate(dr.astype(np.float32), dt.astype(np.float32), "LDR", applyMagma=False)
        m = np.asarray(m)
        entry["flip"] = {"mean": float(mean), "weighted_median": weighted(m, 0.5), "weighted_q1": weighted(m, 0.25), "weighted_q3": weighted(m, 0.75), "max": float(m.max())}
        entry["ssim"] = float(structural_similarity(dr, dt, gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0, channel_axis=-1))
        entry["psnr"] = float(peak_signal_noise_ratio(dr, dt, data_range=1.0))
        out["pairs"][name] = entry
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
