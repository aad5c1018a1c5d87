#!/usr/bin/env python3
"""Mitsuba 3's ray tracing (Embree on its LLVM variant) on the rays that
`examples/traversal_counts.rs --dump DIR` wrote, on one thread: nanoseconds per ray of
`Scene.ray_intersect_preliminary` (closest hit, no surface interaction) and
`Scene.ray_test` (any hit), best of three after a warm-up that compiles the kernels.

Usage: DRJIT_LIBLLVM_PATH=... python scripts/traversal_vs_embree.py SCENE.xml DIR
[--threads N] (default 1, to compare with the example's one thread)."""
import argparse
import os
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("dir")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    a = ap.parse_args()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(a.variant)
    dr.set_thread_count(a.threads)
    scene = mi.load_file(a.scene)
    print(f"{a.scene}: Mitsuba {mi.__version__} {a.variant}, {a.threads} thread(s)")
    print("rays               closest ns  any ns  closest misses")
    for name in ["primary", "diffuse", "primary_shuffled", "diffuse_shuffled"]:
        o = np.fromfile(os.path.join(a.dir, f"{name}.o.f32"), dtype="<f4").reshape(-1, 4)
        d = np.fromfile(os.path.join(a.dir, f"{name}.d.f32"), dtype="<f4").reshape(-1, 4)
        n = len(o)
        ray = mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
        dr.eval(ray)

        def closest():
            pi = scene.ray_intersect_preliminary(ray, coherent=False)
            dr.eval(pi.t)
            dr.sync_thread()  # the LLVM backend launches asynchronously
            return pi.t

        def any_hit():
            h = scene.ray_test(ray)
            dr.eval(h)
            dr.sync_thread()
            return h

        res = {}
        for label, f in [("closest", closest), ("any", any_hit)]:
            out = f()  # compiles the kernel
            best = float("inf")
            for _ in range(3):
                t0 = time.perf_counter()
                out = f()
                best = min(best, time.perf_counter() - t0)
            res[label] = (best * 1e9 / n, out)
        misses = int(dr.count(~dr.isfinite(res["closest"][1]))[0])
        print(f"{name:17} {res['closest'][0]:11.1f} {res['any'][0]:7.1f} {misses:15d}")


if __name__ == "__main__":
    main()
