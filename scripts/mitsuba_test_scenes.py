#!/usr/bin/env python3
"""Mitsuba's own render test (`src/render/tests/test_renders.py`), run on Cohort with
Mitsuba's own test scenes: those of a `mitsuba-data` checkout (the `resources/data`
submodule of Mitsuba 3), with the references it holds.

For each `tests/scenes/<folder>/<name>_<integrator>.xml` that has
`refs/<name>_ref_rgb.exr` and `_var.exr` (participating media excluded: Cohort has no
volumes), renders the scene as Mitsuba's test does (`-D spp=N -D integrator=<integrator>`,
N = 2e6 / pixels) and applies Mitsuba's z-test in CIE XYZ: at least 99.75 % of the pixel
channels must pass at the Sidak-corrected significance 1 %. Prints one verdict per scene
and the count; exits 1 if any scene fails or does not render.

Usage: scripts/mitsuba_test_scenes.py MITSUBA_DATA [--cohort PATH] [--backend B] [names...]
  (MITSUBA_DATA: a clone of https://github.com/mitsuba-renderer/mitsuba-data; the scenes
  read meshes and textures from its `common/` folder. Needs numpy and the `mitsuba`
  package, to read EXR files and for its erf.)
"""

import argparse
import glob
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

SRGB_TO_XYZ = np.array(
    [
        [0.412453, 0.357580, 0.180423],
        [0.212671, 0.715160, 0.072169],
        [0.019334, 0.119193, 0.950227],
    ]
)


def read_xyz(mi, path):
    """The first three channels of an EXR (linear sRGB), in CIE XYZ."""
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3] @ SRGB_TO_XYZ.T


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data")
    ap.add_argument("--cohort", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "cohort"))
    ap.add_argument("--backend", default=None)
    ap.add_argument("names", nargs="*")
    a = ap.parse_intermixed_args()
    if not os.path.isfile(a.cohort):
        sys.exit(f"no cohort binary at {a.cohort}: build it first (cargo build --release -p cohort-cli) "
                 "or pass --cohort PATH")
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scenes = sorted(glob.glob(os.path.join(a.data, "tests", "scenes", "*", "*.xml")))
    passed = failed = 0
    out_dir = tempfile.mkdtemp(prefix="cohort-mitsuba-tests-")
    for xml in scenes:
        if "participating_media" in xml or "volprim" in xml:
            continue
        base = os.path.splitext(os.path.basename(xml))[0]
        if a.names and not any(n in base for n in a.names):
            continue
        name, integrator = base.rsplit("_", 1)
        ref = os.path.join(os.path.dirname(xml), "refs", f"{name}_ref_rgb.exr")
        var = ref.replace(".exr", "_var.exr")
        if not (os.path.exists(ref) and os.path.exists(var)):
            continue
        reference, variance = read_xyz(mi, ref), read_xyz(mi, var)
        pixels = reference.shape[0] * reference.shape[1]
        spp = int(2e6) // pixels
        out = os.path.join(out_dir, f"{base}.exr")
        cmd = [a.cohort, "render", "--scene", xml, "-D", f"spp={spp}", "-D", f"integrator={integrator}",
               "--paths", str(spp), "--out", out, "--png", out.replace(".exr", ".png")]
        if a.backend:
            cmd += ["--backend", a.backend]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            last = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
            print(f"{base}: ERROR {last}")
            failed += 1
            continue
        image = read_xyz(mi, out)
        z = np.abs(image - reference) * np.sqrt(spp / np.maximum(variance, 1e-4))
        p_value = np.vectorize(lambda x: math.erfc(x / math.sqrt(2.0)))(z)
        alpha = 1.0 - (1.0 - 0.01) ** (1.0 / pixels)
        ok = int((p_value > alpha).sum())
        verdict = ok / 3 >= 0.9975 * pixels
        passed += verdict
        failed += not verdict
        print(f"{base}: {'PASS' if verdict else 'FAIL'} {ok}/{3 * pixels} pixel channels "
              f"(min p-value {p_value.min():.3e}, significance {alpha:.3e})", flush=True)
    print(f"{passed} of {passed + failed} scenes pass Mitsuba's render test")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
