#!/usr/bin/env python3
"""Writes kernels/tests/data/microfacet_mitsuba.txt: Mitsuba 3.9.1's own microfacet
distribution (`mi.MicrofacetDistribution`, the `mitsuba` Python package, scalar_rgb) and its
`roughconductor` BSDF, at random directions and samples, for kernels/tests/microfacet.rs to
compare `cohort_kernels::microfacet` with.

Lines: `D beckmann alpha_u alpha_v` starts a distribution (0: GGX, 1: Beckmann);
`C wi.xyz wo.xyz u.xy m.xyz pdf_m value pdf` is one case in the local frame (wi towards the
viewer): the visible normal `m` Mitsuba samples from `u` and its density, and its
`roughconductor` (material none, specular reflectance 1) at (wi, wo): f·cos and the density.

Usage: scripts/microfacet_cases.py
"""

import os
import random

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "kernels", "tests", "data", "microfacet_mitsuba.txt")

SETS = [(0, 0.3, 0.3), (1, 0.3, 0.3), (0, 0.25, 0.05), (1, 0.05, 0.3), (1, 0.6, 0.2), (0, 0.02, 0.7)]
CASES = 80


def direction(rng):
    while True:
        v = [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.02, 1)]
        n = sum(x * x for x in v) ** 0.5
        if 0.1 < n <= 1:
            return [x / n for x in v]


def main():
    mi.set_variant("scalar_rgb")
    rng = random.Random(11)
    lines = []
    for beckmann, au, av in SETS:
        kind = mi.MicrofacetType.Beckmann if beckmann else mi.MicrofacetType.GGX
        distr = mi.MicrofacetDistribution(kind, au, av, True)
        bsdf = mi.load_dict({"type": "roughconductor", "distribution": "beckmann" if beckmann else "ggx",
                             "alpha_u": au, "alpha_v": av})
        lines.append(f"D {beckmann} {au!r} {av!r}")
        ctx = mi.BSDFContext()
        for _ in range(CASES):
            wi = direction(rng)
            wo = direction(rng)
            u = [rng.random(), rng.random()]
            m, pdf_m = distr.sample(mi.Vector3f(wi), mi.Point2f(u))
            si = mi.SurfaceInteraction3f()
            si.p = [0, 0, 0]
            si.n = [0, 0, 1]
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.wi = mi.Vector3f(wi)
            value = bsdf.eval(ctx, si, mi.Vector3f(wo))
            pdf = bsdf.pdf(ctx, si, mi.Vector3f(wo))
            row = wi + wo + u + [m[0], m[1], m[2], pdf_m, value[0], pdf]
            lines.append(" ".join(["C"] + [repr(float(x)) for x in row]))
    with open(OUT, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {OUT}: {len(SETS)} distributions x {CASES} cases")


if __name__ == "__main__":
    main()
