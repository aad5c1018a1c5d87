#!/usr/bin/env python3
"""Where Cohort's expected image differs from Mitsuba 3's on the same scene file: two long
Mitsuba renders (seeds 1 and 2) and two long Cohort renders (seeds 1 and 2) of each scene.
The pairs' differences measure each renderer's own noise, so what is left of Cohort minus
Mitsuba beyond both noises is bias. Prints, per scene: the mean of each image and their ratio
by channel; the relative RMS of each difference; the RMS bias left after removing both
noises; and the blocks (16x16 pixels) where the two renderers' means differ most, in units
of the noise of that difference. Writes OUT/<scene>_bias.png: the block means' relative
difference (red: Cohort brighter, blue: Mitsuba brighter, full scale +-5 %) beside
Mitsuba's image.

usage: bias_vs_mitsuba.py --scenes DIR --names cornell-box,bunny-box --cohort bin/cohort
       [--size 256] [--spp 16384] [--variant cuda_ad_rgb] [--cohort-args "--backend vulkan"]
       [--out DIR]
"""
import argparse, os, shlex, subprocess, sys, tempfile

import numpy as np

# The scene loading and the timed Mitsuba render of the equal-time benchmark, beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from equal_time import load_scene, mitsuba_render, read_exr  # noqa: E402


def cohort(mi, binary, path, size, spp, seed, extra, tmp):
    exr = os.path.join(tmp, "c%d.exr" % seed)
    cmd = [binary, "render", "--scene", path, "--width", str(size), "--height", str(size),
           "--paths", str(spp), "--seed", str(seed), "--out", exr,
           "--png", os.path.join(tmp, "c.png")] + shlex.split(extra)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("cohort failed: %s\n%s" % (" ".join(cmd), r.stderr))
    return read_exr(mi, exr)


def blocks(img, b):
    h, w = img.shape[0] // b * b, img.shape[1] // b * b
    return img[:h, :w].reshape(h // b, b, w // b, b, -1).mean(axis=(1, 3))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", required=True)
    ap.add_argument("--names", default="cornell-box,bunny-box")
    ap.add_argument("--cohort", required=True)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=16384)
    ap.add_argument("--variant", default="cuda_ad_rgb")
    ap.add_argument("--cohort-args", default="--backend vulkan --integrator nee")
    ap.add_argument("--out", default=".")
    a = ap.parse_args()
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(a.variant)
    os.makedirs(a.out, exist_ok=True)
    b = 16
    for name in a.names.split(","):
        path = os.path.join(a.scenes, name, "scene.xml")
        scene = load_scene(mi, path, a.size, a.spp)
        with tempfile.TemporaryDirectory() as tmp:
            m1, m2 = (mitsuba_render(mi, dr, scene, a.spp, s)[0] for s in (1, 2))
            c1, c2 = (cohort(mi, a.cohort, path, a.size, a.spp, s, a.cohort_args, tmp) for s in (1, 2))
        mean = m1.mean()
        rel = lambda x: float(np.sqrt(np.mean(x ** 2)) / mean)
        noise_m, noise_c = rel(m1 - m2) / np.sqrt(2), rel(c1 - c2) / np.sqrt(2)
        # Cohort's mean minus Mitsuba's mean: noise var (noise_c^2 + noise_m^2) / 2 per pixel.
        diff = (c1 + c2) / 2 - (m1 + m2) / 2
        total = rel(diff)
        bias = np.sqrt(max(total ** 2 - (noise_c ** 2 + noise_m ** 2) / 2, 0.0))
        print("%s, %dx%d, %d spp each (four renders)" % (name, a.size, a.size, a.spp))
        print("  image mean by channel: mitsuba %s cohort %s ratio %s" % (
            np.round((m1 + m2).mean(axis=(0, 1)) / 2, 5), np.round((c1 + c2).mean(axis=(0, 1)) / 2, 5),
            np.round((c1 + c2).mean(axis=(0, 1)) / (m1 + m2).mean(axis=(0, 1)), 5)))
        print("  relative RMS of one render's noise at this spp: mitsuba %.5f cohort %.5f (cohort / mitsuba %.3f)" % (
            noise_m, noise_c, noise_c / noise_m))
        print("  relative RMS of cohort - mitsuba (means of two): %.5f; bias beyond both noises: %.5f" % (total, bias))
        # Blocks: difference of means, and its noise from the pairs' differences.
        d_b = blocks(diff, b).mean(axis=2)
        noise_b = np.sqrt((blocks((c1 - c2) ** 2, b) + blocks((m1 - m2) ** 2, b)).mean(axis=2) / 4 / (b * b))
        ref_b = blocks((m1 + m2) / 2, b).mean(axis=2)
        z = d_b / np.maximum(noise_b, 1e-12)
        order = np.argsort(-np.abs(z), axis=None)[:10]
        print("  blocks (%dx%d px) differing most: (row, col) relative difference, z" % (b, b))
        for k in order:
            r, c = divmod(int(k), z.shape[1])
            print("    (%2d, %2d) %+.4f  z %+.1f" % (r, c, d_b[r, c] / max(ref_b[r, c], 1e-12), z[r, c]))
        print("  blocks with |z| > 4: %d of %d" % (int((np.abs(z) > 4).sum()), z.size))
        # Heat map beside the image, each block drawn 16x16.
        rel_b = np.clip(d_b / np.maximum(ref_b, 1e-12) / 0.05, -1, 1)
        heat = np.zeros(rel_b.shape + (3,))
        heat[..., 0] = np.maximum(rel_b, 0)
        heat[..., 2] = np.maximum(-rel_b, 0)
        heat = np.kron(heat, np.ones((b, b, 1)))
        img = np.clip((m1 + m2) / 2, 0, 1)[: heat.shape[0], : heat.shape[1]]
        both = np.concatenate([img, heat], axis=1)
        mi.util.write_bitmap(os.path.join(a.out, "%s_bias.png" % name), both.astype(np.float32), write_async=False)


if __name__ == "__main__":
    main()
