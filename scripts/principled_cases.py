#!/usr/bin/env python3
"""Writes kernels/tests/data/principled_mitsuba.txt: Mitsuba 3.9.1's own `principled` and
`principledthin` BSDFs (the `mitsuba` Python package, scalar_rgb) evaluated and sampled at
random directions and samples, for kernels/tests/principled.rs to compare the kernels'
functions with.

Lines: `P thin r g b roughness anisotropic metallic spec_trans spec_tint sheen sheen_tint
clearcoat clearcoat_gloss flatness diff_trans eta` starts a parameter set (eta as Mitsuba
derives it); `C wi.xyz wo.xyz value.rgb pdf s1 s2.xy sampled_wo.xyz weight.rgb` is one
case in the local shading frame (wi towards the viewer).

Usage: scripts/principled_cases.py
"""

import os
import random

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "kernels", "tests", "data", "principled_mitsuba.txt")

NAMES = ["roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen", "sheen_tint",
         "clearcoat", "clearcoat_gloss", "flatness", "diff_trans"]
SETS = [
    ("principled", (0.8, 0.2, 0.1), dict(roughness=0.4, metallic=0.3, spec_tint=0.5, sheen=0.6, sheen_tint=0.5,
                                         clearcoat=0.7, clearcoat_gloss=0.4, flatness=0.3)),
    ("principled", (0.9, 0.7, 0.3), dict(roughness=0.35, anisotropic=0.7, metallic=0.8, specular=0.7)),
    ("principled", (0.9, 0.8, 0.6), dict(spec_trans=0.85, roughness=0.25, eta=1.4, clearcoat=0.3)),
    ("principled", (0.3, 0.7, 0.5), dict(spec_trans=0.5, metallic=0.2, roughness=0.5, spec_tint=0.3)),
    ("principledthin", (0.3, 0.8, 0.2), dict(spec_trans=0.4, diff_trans=0.8, roughness=0.3, eta=1.3, sheen=0.4,
                                             spec_tint=0.5)),
    ("principledthin", (0.8, 0.5, 0.3), dict(diff_trans=1.2, flatness=0.5, roughness=0.6)),
]
CASES = 60


def direction(rng):
    while True:
        v = [rng.uniform(-1, 1) for _ in range(3)]
        n = sum(x * x for x in v) ** 0.5
        if 0.1 < n <= 1:
            return [x / n for x in v]


def main():
    mi.set_variant("scalar_rgb")
    rng = random.Random(5)
    lines = []
    for plugin, base, params in SETS:
        d = {"type": plugin, "base_color": {"type": "rgb", "value": list(base)}}
        d.update(params)
        bsdf = mi.load_dict(d)
        if plugin == "principled":
            eta = params.get("eta")
            if eta is None:
                s = params.get("specular", 0.5)
                eta = 2.0 / (1.0 - (0.08 * s) ** 0.5) - 1.0
        else:
            eta = params.get("eta", 1.5)
        values = [params.get(n, 0.5 if n == "roughness" else 0.0) for n in NAMES]
        lines.append(" ".join(["P", "1" if plugin == "principledthin" else "0"]
                              + [repr(float(x)) for x in base] + [repr(float(x)) for x in values]
                              + [repr(float(eta))]))
        ctx = mi.BSDFContext()
        for _ in range(CASES):
            si = mi.SurfaceInteraction3f()
            si.p = [0, 0, 0]
            si.n = [0, 0, 1]
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.uv = [0.5, 0.5]
            wi = direction(rng)
            wo = direction(rng)
            si.wi = mi.Vector3f(wi)
            value = bsdf.eval(ctx, si, mi.Vector3f(wo))
            pdf = bsdf.pdf(ctx, si, mi.Vector3f(wo))
            s1 = rng.random()
            s2 = [rng.random(), rng.random()]
            bs, weight = bsdf.sample(ctx, si, s1, mi.Point2f(s2))
            row = (wi + wo + [value[0], value[1], value[2], pdf, s1] + s2
                   + [bs.wo[0], bs.wo[1], bs.wo[2], weight[0], weight[1], weight[2]])
            lines.append(" ".join(["C"] + [repr(float(x)) for x in row]))
    with open(OUT, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {OUT}: {len(SETS)} parameter sets x {CASES} cases")


if __name__ == "__main__":
    main()
