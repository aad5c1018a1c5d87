#!/usr/bin/env python3
"""Where the error of an equal-error comparison lies: the share of a short Mitsuba 3 render's
squared error (against a long one) in the pixels that an emitter covers at least in part, and
in those pixels and their eight neighbours. A camera ray that hits a bright emitter in one
sample and a wall in the next makes these pixels noisy whatever the light transport costs,
so where they hold most of the error, a renderer's time to that error measures how fast it
antialiases the emitter's outline (with independent pixel samples, the same for both
renderers) more than how fast it traces paths. Also prints the error of the direct lighting
alone (Mitsuba's `max_depth` 2) against the same reference's mean.

Coverage is found geometrically: 4x4 camera rays per pixel, a pixel covered when one of them
hits a surface with an emitter.

usage: DRJIT_LIBLLVM_PATH=... python scripts/error_near_emitters.py SCENE.xml [SCENE.xml ...]
       [--size 256] [--spp 32] [--ref-spp 2048] [--seeds 1,2] [--variant llvm_ad_rgb]
"""
import argparse, os, sys

import numpy as np

# The scene loading and the timed Mitsuba render of the equal-time benchmark, beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from equal_time import load_scene, mitsuba_render  # noqa: E402


def emitter_pixels(mi, dr, scene, size, sub=4):
    """Boolean size x size mask of the pixels that an emitter covers at least in part."""
    sensor = scene.sensors()[0]
    n = size * sub
    idx = np.arange(n * n)
    x = (idx % n + 0.5) / n
    y = (idx // n + 0.5) / n
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(x.astype(np.float32), y.astype(np.float32)),
                               mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    hit = np.array(si.is_valid() & si.shape.is_emitter())
    return hit.reshape(size, sub, size, sub).any(axis=(1, 3))


def dilate(mask):
    out = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    a = ap.parse_args()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(a.variant)
    print(f"Mitsuba {mi.__version__} {a.variant}, {a.size}x{a.size}, {a.spp} spp against {a.ref_spp}")
    print("| scene | seed | RMS % | emitter pixels | their share of squared error | with neighbours | RMS % without those | direct lighting only, RMS % |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for path in a.scenes:
        name = os.path.basename(os.path.dirname(os.path.abspath(path)))
        scene = load_scene(mi, path, a.size, 1)
        passes = max(1, a.ref_spp // 256)
        ref = sum(mitsuba_render(mi, dr, scene, a.ref_spp // passes, 100000 + p)[0] for p in range(passes)) / passes
        direct = mi.load_dict({"type": "path", "max_depth": 2})
        dref = sum(np.array(mi.render(scene, integrator=direct, spp=a.ref_spp // passes, seed=200000 + p))[:, :, :3]
                   for p in range(passes)) / passes
        on = emitter_pixels(mi, dr, scene, a.size)
        near = dilate(on)
        mean = ref.mean()
        for seed in [int(s) for s in a.seeds.split(",")]:
            img, _ = mitsuba_render(mi, dr, scene, a.spp, seed)
            e2 = ((img - ref) ** 2).sum(axis=2)
            total = e2.sum()
            rest = np.sqrt(e2[~near].sum() / e2.size / 3) / mean
            dimg = np.array(mi.render(scene, integrator=direct, spp=a.spp, seed=seed))[:, :, :3]
            drms = np.sqrt(np.mean((dimg - dref) ** 2)) / mean
            print(f"| {name} | {seed} | {100 * np.sqrt(total / e2.size / 3) / mean:.2f} | {int(on.sum())} | "
                  f"{e2[on].sum() / total:.3f} | {e2[near].sum() / total:.3f} | {100 * rest:.2f} | {100 * drms:.2f} |",
                  flush=True)


if __name__ == "__main__":
    main()
