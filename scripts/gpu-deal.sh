#!/usr/bin/env bash
# Dealing paths to finished slots (`--deal`) on one GPU: cornell-box and stanford-like at
# 256, 512 and 1024 square, 32 paths per pixel, next-event estimation, `--deal off` and
# `--deal on` alternated $ROUNDS times (default 3) after one warm-up render of each, then
# the median kernel and wall time of each and their ratios. Whether the two images are the
# same up to float rounding, and two renders that deal the same bit for bit, is checked once
# per scene and size (`cohort compare`). Needs $B/cohort or
# $B/cohort.xz (release, stripped; B defaults to bin-gpu). On the device:
#   OUT=$OUT scripts/gpu-deal.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
B="${B:-bin-gpu}"; SCENES="${SCENES:-render/tests/scenes}"; ROUNDS="${ROUNDS:-3}"
if [ -f "$B/cohort.xz" ] && [ ! -x "$B/cohort" ]; then
  (cd "$B" && xz -dkf cohort.xz && chmod +x cohort) || exit 1
fi
export COHORT_VK_VALIDATION=0
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 1000 > "$OUT/clocks.csv" &
SMI=$!
tmp=$(mktemp -d)
run() { # scene size deal tag
  "$B/cohort" render --backend vulkan --scene "$SCENES/$1/scene.xml" --integrator nee --paths 32 \
    --width "$2" --height "$2" --deal "$3" --out "$tmp/$1-$2-$3.exr" --png "$tmp/p.png" 2>&1 |
    grep -E '^(kernel time|paths/pixel|dealt|wall)' | tr '\n' ' ' | sed "s/^/$4 $1 $2 $3 /"; echo
}
for s in cornell-box stanford-like; do for z in 256 512 1024; do for d in off on; do run $s $z $d warm >/dev/null; done; done; done
for r in $(seq "$ROUNDS"); do
  for s in cornell-box stanford-like; do for z in 256 512 1024; do for d in off on; do run $s $z $d "round$r"; done; done; done
done | tee "$OUT/deal.log"
# Off against on (the same up to float rounding), and on against on again (bit for bit:
# the retirements fall at the same iterations).
for s in cornell-box stanford-like; do for z in 256 512 1024; do
  cp "$tmp/$s-$z-on.exr" "$tmp/first.exr"; run $s $z on again >/dev/null
  echo "$s $z: off/on $("$B/cohort" compare "$tmp/$s-$z-off.exr" "$tmp/$s-$z-on.exr" 2>&1 | tail -1);" \
    "on/on $("$B/cohort" compare "$tmp/first.exr" "$tmp/$s-$z-on.exr" 2>&1 | grep -E '^bit-identical' )"
done; done | tee "$OUT/compare.log"
kill $SMI
python3 - "$OUT/deal.log" <<'PY' | tee "$OUT/summary.txt"
import re, statistics, sys
t = {}
for line in open(sys.argv[1]):
    f = line.split()
    if len(f) < 6: continue
    ms = float(re.search(r"kernel time\s+([\d.]+) ms", line).group(1))
    wall = float(re.search(r"wall\s+([\d.]+) s", line).group(1)) * 1e3
    t.setdefault((f[1], f[2], f[3]), []).append((ms, wall))
for (s, z, d), v in sorted(t.items()):
    if d != "off": continue
    med = lambda xs, i: statistics.median(x[i] for x in xs)
    w = t[(s, z, "on")]
    off, on, woff, won = med(v, 0), med(w, 0), med(v, 1), med(w, 1)
    print(f"{s:14} {z:>5}  kernel off {off:7.2f} ms  on {on:7.2f} ms  on/off {on/off:.3f}"
          f"  wall off {woff:6.0f} ms  on {won:6.0f} ms  on/off {won/woff:.3f}")
PY
