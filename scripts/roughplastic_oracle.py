#!/usr/bin/env python3
"""Mitsuba 3.9.1's `roughplastic` (scalar_rgb), evaluated for the cases of
kernels/tests/rough_plastic.rs: f·cos and the density for a few incident and outgoing
local directions. Prints Rust array literals to paste there.

Usage: pip install mitsuba==3.9.1 && scripts/roughplastic_oracle.py
"""

import math

import drjit as dr
import mitsuba as mi

mi.set_variant("scalar_rgb")

# (distribution, alpha, int_ior, ext_ior, diffuse rgb, nonlinear)
CONFIGS = [
    ("ggx", 0.3, 1.5, 1.0, (0.6, 0.3, 0.1), False),
    ("ggx", 0.05, 1.49, 1.000277, (0.5, 0.5, 0.5), True),
    ("beckmann", 0.2, 1.7, 1.0, (0.2, 0.7, 0.4), True),
    ("beckmann", 0.6, 1.33, 1.0, (0.9, 0.9, 0.9), False),
]


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))


# (wi = towards the viewer, wo = the scattered direction), Mitsuba's names.
PAIRS = [
    (direction(10, 0), direction(10, 180)),
    (direction(45, 30), direction(45, 210)),
    (direction(60, 0), direction(20, 90)),
    (direction(80, 0), direction(75, 180)),
    (direction(30, 0), direction(85, 45)),
]

for dist, alpha, int_ior, ext_ior, diffuse, nonlinear in CONFIGS:
    bsdf = mi.load_dict(
        {
            "type": "roughplastic",
            "distribution": dist,
            "alpha": alpha,
            "int_ior": int_ior,
            "ext_ior": ext_ior,
            "diffuse_reflectance": {"type": "rgb", "value": diffuse},
            "nonlinear": nonlinear,
        }
    )
    ctx = mi.BSDFContext()
    print(f"// {dist} alpha {alpha} eta {int_ior}/{ext_ior} diffuse {diffuse} nonlinear {nonlinear}")
    for wi, wo in PAIRS:
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.wi = mi.Vector3f(wi)
        v = bsdf.eval(ctx, si, mi.Vector3f(wo))
        p = bsdf.pdf(ctx, si, mi.Vector3f(wo))
        print(
            f"([{wi[0]:.7}, {wi[1]:.7}, {wi[2]:.7}], [{wo[0]:.7}, {wo[1]:.7}, {wo[2]:.7}], "
            f"[{v[0]:.7e}, {v[1]:.7e}, {v[2]:.7e}], {p:.7e}),"
        )

# The external transmittance table entries (k / 63 = cos θ), by Mitsuba's own algorithm
# (`eval_transmittance` in include/mitsuba/render/microfacet.h: 32 x 32 Gauss-Legendre
# nodes over its visible-normal sampling), through the package's functions.
print("// transmittance tables: (distribution, alpha, eta, [(k, t)])")
nodes, weights = mi.quad.gauss_legendre(32)
nodes, weights = list(nodes), list(weights)
for dist, alpha, eta in [("ggx", 0.3, 1.5), ("beckmann", 0.2, 1.7)]:
    kind = mi.MicrofacetType.GGX if dist == "ggx" else mi.MicrofacetType.Beckmann
    distr = mi.MicrofacetDistribution(kind, alpha, True)
    entries = []
    for k in [0, 5, 10, 32, 50, 63]:
        mu = max(1e-6, k / 63)
        wi = mi.Vector3f(math.sqrt(1 - mu * mu), 0, mu)
        t = 0.0
        for i in range(32):
            for j in range(32):
                node = mi.Point2f(nodes[j] * 0.5 + 0.5, nodes[i] * 0.5 + 0.5)
                m = distr.sample(wi, node)[0]
                f, cos_t, _, eta_ti = mi.fresnel(dr.dot(wi, m), eta)
                wo = mi.refract(wi, m, cos_t, eta_ti)
                if wo.z * wi.z < 0:
                    t += distr.smith_g1(wo, m) * (1 - f) * weights[j] * weights[i] * 0.25
        entries.append(f"({k}, {t:.7})")
    print(f'("{dist}", {alpha}, {eta}, [{", ".join(entries)}]),')
