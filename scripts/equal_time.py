#!/usr/bin/env python3
"""Equal-time benchmark (image quality against Mitsuba 3): Mitsuba 3 and Cohort render the same
Mitsuba XML scenes on the same GPU in the same run; RMS error of every image against Mitsuba's
own long reference, versus time. Writes equal_time.csv, equal_time.md and equal_time.png into
--out.

RMS is relative: sqrt(mean over pixels and channels of (img - ref)^2) / mean(ref), as
`cohort figures` computes it. References: a long Mitsuba render and a long Cohort render, each
with seeds no timed render uses. With `--reference cross` (the default) each renderer's error
is taken against the other's reference, so that no render can share random numbers with its
reference, whatever either renderer does with its seeds (measured on bunny-box, cornell-box
and stanford-like at 512x512: the two references' means agree to 0.025 % and the errors
against them differ by at most 0.2 points). `--reference mitsuba` takes both against
Mitsuba's, as before 2026-11-28; the CSV has both errors (`rms_vs_mitsuba_ref`,
`rms_vs_cohort_ref`). RMS error is dominated by a few noisy pixels, so one seed's error moves
by several percent: give Cohort several seeds (`--seed N` in configurations separated by `;`)
and Mitsuba too (`--mitsuba-seeds 1,2,3`: the target error is then the RMS over its seeds, at
the mean of their times). Times: Mitsuba's is the wall time of `mi.render` plus the
synchronisation that waits for the GPU (after an untimed warm-up render, so JIT compilation
is cached); Cohort's is its render wall time (`wall_s` of --stats, the loop that keeps the
GPU busy, after scene load and pipeline creation), and the whole process wall time is
recorded beside it.

usage: equal_time.py --scenes DIR --cohort bin/cohort [--variant cuda_ad_rgb] [--size 1024]
       [--ref-spp 4096,2048] [--mitsuba-spp 32,64,128,256,512] [--cohort-paths 32,64,128,256,512,1024]
       [--cohort-args "--integrator nee"] [--target-spp 256] [--reference cross|mitsuba]
       [--mitsuba-seeds 1,2,3] [--out DIR]
"""
import argparse, csv, json, math, os, shlex, subprocess, sys, tempfile, time

import numpy as np


def rms(img, ref):
    return float(np.sqrt(np.mean((img - ref) ** 2)) / np.mean(ref))


def load_scene(mi, path, size, spp):
    # The shared scenes set width/height/sample_count literally: override through a copy of
    # the XML next to the original, so relative mesh paths still resolve.
    text = open(path).read()
    import re
    text = re.sub(r'(<integer name="width" value=")\d+', r'\g<1>%d' % size, text)
    text = re.sub(r'(<integer name="height" value=")\d+', r'\g<1>%d' % size, text)
    text = re.sub(r'(<integer name="sample_count" value=")\d+', r'\g<1>%d' % spp, text)
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)), ".equal_time_scene.xml")
    open(tmp, "w").write(text)
    try:
        return mi.load_file(tmp)
    finally:
        os.remove(tmp)


def mitsuba_render(mi, dr, scene, spp, seed):
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    t = time.perf_counter() - t0
    return np.array(img)[:, :, :3].astype(np.float64), t


def read_exr(mi, path):
    return np.array(mi.Bitmap(path))[:, :, :3].astype(np.float64)


def without_seed(args):
    """Cohort options less any `--seed N` (the reference has a seed of its own)."""
    out, skip = [], False
    for x in args:
        if skip:
            skip = False
        elif x == "--seed":
            skip = True
        elif not x.startswith("--seed="):
            out.append(x)
    return out


def interpolate_time(points, target):
    """Time at which the (time, rms) curve reaches `target` (log-log interpolation)."""
    pts = sorted(points)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            a = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + a * (math.log(t1) - math.log(t0)))
    if pts and pts[0][1] <= target:
        return pts[0][0]  # already below at the first point: an upper bound
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", required=True, help="folder holding cornell-box/ and stanford-like/")
    ap.add_argument("--names", default="cornell-box,stanford-like")
    ap.add_argument("--cohort", default="target/release/cohort")
    ap.add_argument("--variant", default="cuda_ad_rgb")
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--ref-spp", default="4096,2048")
    ap.add_argument("--mitsuba-spp", default="32,64,128,256,512")
    ap.add_argument("--cohort-paths", default="32,64,128,256,512,1024")
    ap.add_argument("--cohort-args", default="--integrator nee", help="Cohort options; several configurations separated by ';'")
    ap.add_argument("--target-spp", type=int, default=256, help="the ratio is taken at the RMS of Mitsuba's render at this many spp")
    ap.add_argument("--mitsuba-seeds", default="1", help="Mitsuba's timed renders for each of these seeds (1..999); the target is over all")
    ap.add_argument("--reference", choices=["cross", "mitsuba"], default="cross",
                    help="cross: each renderer against the other's reference; mitsuba: both against Mitsuba's")
    ap.add_argument("--out", default=os.environ.get("OUT", "equal-time-out"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(a.variant)
    rows = []
    names = a.names.split(",")
    ref_spp = [int(x) for x in a.ref_spp.split(",")]
    for k, name in enumerate(names):
        xml = os.path.join(a.scenes, name, "scene.xml")
        spp_ref = ref_spp[min(k, len(ref_spp) - 1)]
        scene = load_scene(mi, xml, a.size, 1)
        mitsuba_render(mi, dr, scene, 4, 7)  # warm-up: JIT compilation
        # The reference in 256-spp passes (bounded memory), seeds distinct from the timed renders.
        passes = max(1, spp_ref // 256)
        acc = None
        t0 = time.perf_counter()
        for p in range(passes):
            img, _ = mitsuba_render(mi, dr, scene, spp_ref // passes, 100000 + p)
            acc = img if acc is None else acc + img
        ref = acc / passes
        print(f"{name}: reference {spp_ref} spp in {time.perf_counter() - t0:.1f} s, mean {ref.mean():.4f}", flush=True)
        with tempfile.TemporaryDirectory() as td:
            # Cohort's reference: the first configuration, as many paths, a seed of its own.
            exr = os.path.join(td, "ref.exr")
            cmd = [a.cohort, "render", "--scene", xml, "--width", str(a.size), "--height", str(a.size), "--paths", str(spp_ref),
                   "--seed", "1000003", "--out", exr, "--png", os.path.join(td, "ref.png")] + without_seed(shlex.split(a.cohort_args.split(";")[0]))
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            cref = read_exr(mi, exr)
        print(f"{name}: Cohort reference {spp_ref} paths, mean {cref.mean():.4f} (Mitsuba's / Cohort's {ref.mean() / cref.mean():.5f})", flush=True)

        def errors(img, own):
            e = dict(rms_vs_mitsuba_ref=rms(img, ref), rms_vs_cohort_ref=rms(img, cref))
            other = "rms_vs_cohort_ref" if own == "mitsuba" else "rms_vs_mitsuba_ref"
            e["rms"] = e[other] if a.reference == "cross" else e["rms_vs_mitsuba_ref"]
            return e

        seeds = [int(x) for x in a.mitsuba_seeds.split(",")]
        for k in seeds:
            label = "mitsuba " + a.variant + (f" seed {k}" if len(seeds) > 1 else "")
            for spp in [int(x) for x in a.mitsuba_spp.split(",")]:
                # Seed 1 keeps the seeds of the figures before --mitsuba-seeds (1 + spp).
                img, t = mitsuba_render(mi, dr, scene, spp, (k - 1) * 1000 + 1 + spp)
                rows.append(dict(scene=name, renderer=label, budget=f"{spp} spp", seconds=t, process_seconds=t, mean=img.mean(), **errors(img, "mitsuba")))
                print(rows[-1], flush=True)
        del scene
        with tempfile.TemporaryDirectory() as td:
          for cargs in a.cohort_args.split(";"):
            for paths in [int(x) for x in a.cohort_paths.split(",")]:
                exr, stats = os.path.join(td, "c.exr"), os.path.join(td, "c.json")
                cmd = [a.cohort, "render", "--scene", xml, "--width", str(a.size), "--height", str(a.size), "--paths", str(paths),
                       "--out", exr, "--png", os.path.join(td, "c.png"), "--stats", stats] + shlex.split(cargs)
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                pt = time.perf_counter() - t0
                s = json.load(open(stats))
                img = read_exr(mi, exr)
                rows.append(dict(scene=name, renderer="cohort " + cargs.strip(), budget=f"{paths} paths", seconds=s["wall_s"], process_seconds=pt,
                                 kernel_seconds=s["kernel_ms"]["total"] / 1e3, mean=img.mean(), **errors(img, "cohort")))
                print(rows[-1], flush=True)
    keys = ["scene", "renderer", "budget", "seconds", "process_seconds", "kernel_seconds", "rms", "rms_vs_mitsuba_ref", "rms_vs_cohort_ref", "mean"]
    with open(os.path.join(a.out, "equal_time.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in keys})
    md = [f"RMS % against the {'other renderer' if a.reference == 'cross' else 'Mitsuba'}'s reference (both in the last two columns)", "",
          "| scene | renderer | budget | render s | process s | RMS % | vs Mitsuba's ref | vs Cohort's ref |", "|---|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        md.append(f"| {r['scene']} | {r['renderer']} | {r['budget']} | {r['seconds']:.3f} | {r['process_seconds']:.3f} | {100 * r['rms']:.2f} | {100 * r['rms_vs_mitsuba_ref']:.2f} | {100 * r['rms_vs_cohort_ref']:.2f} |")
    md.append("")
    md.append(f"| scene | Cohort configuration | Mitsuba {a.target_spp}-spp RMS % | Mitsuba s | Cohort s to that RMS (render) | ratio | Cohort s (process) | ratio |")
    md.append("|---|---|---:|---:|---:|---:|---:|---:|")
    for name, label in [(n, l) for n in names for l in sorted({r["renderer"] for r in rows if r["renderer"].startswith("cohort")})]:
        m = [r for r in rows if r["scene"] == name and r["renderer"].startswith("mitsuba")]
        c = [r for r in rows if r["scene"] == name and r["renderer"] == label]
        m256 = [r for r in m if r["budget"] == f"{a.target_spp} spp"]
        if not m256:
            continue
        # Over Mitsuba's seeds: the RMS of their errors, the mean of their times.
        target = math.sqrt(sum(r["rms"] ** 2 for r in m256) / len(m256))
        tm = sum(r["seconds"] for r in m256) / len(m256)
        tc = interpolate_time([(r["seconds"], r["rms"]) for r in c], target)
        tp = interpolate_time([(r["process_seconds"], r["rms"]) for r in c], target)
        fmt = lambda t: "not reached" if t is None else f"{t:.3f}"
        ratio = lambda t: "-" if t is None else f"{t / tm:.2f}"
        md.append(f"| {name} | {label} | {100 * target:.2f} | {tm:.3f} | {fmt(tc)} | {ratio(tc)} | {fmt(tp)} | {ratio(tp)} |")
    open(os.path.join(a.out, "equal_time.md"), "w").write("\n".join(md) + "\n")
    print("\n".join(md))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5))
    for name in names:
        for label in sorted({r["renderer"] for r in rows}):
            pts = sorted((r["seconds"], r["rms"]) for r in rows if r["scene"] == name and r["renderer"] == label)
            if pts:
                ax.loglog([p[0] for p in pts], [100 * p[1] for p in pts], "o-", label=f"{name}: {label}")
    ax.set_xlabel("seconds (render)")
    ax.set_ylabel("RMS error, % of the mean")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "equal_time.png"), dpi=120)


if __name__ == "__main__":
    sys.exit(main())
