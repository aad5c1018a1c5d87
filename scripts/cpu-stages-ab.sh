#!/usr/bin/env bash
# Builds of `cohort` on the CPU backend, alternated, per stage: cornell-box and stanford-like
# at 256x256, 32 paths, next-event estimation (the Mitsuba comparison's renders), $ROUNDS
# times (default 8), then the median kernel time of each build and scene in total and per
# stage (traverse, extend, shadow), in ms. Builds alternate within a round because this
# machine's speed drifts by tens of percent over minutes: only ratios within a run compare.
# An entry BIN:ALGORITHM renders with `--algorithm ALGORITHM` (default `normal`), so that
# coherent configurations compare with `normal` in the same rounds. The last column,
# extend over traverse + shadow per render, compares `extend` between entries whose
# traversals are the same: as a ratio within one render it cancels most of the drift.
# Usage: scripts/cpu-stages-ab.sh BIN[:ALGORITHM]... (at least one; SCENES_DIR, default
# render/tests/scenes).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: $0 BIN[:ALGORITHM]..." >&2; exit 2; }
ROUNDS="${ROUNDS:-8}"
SCENES_DIR="${SCENES_DIR:-render/tests/scenes}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ)"
for r in $(seq "$ROUNDS"); do
  for entry in "$@"; do
    bin="${entry%%:*}"
    alg=normal
    [ "$entry" = "$bin" ] || alg="${entry#*:}"
    for scene in stanford-like cornell-box; do
      line=$("$bin" render --algorithm "$alg" --scene "$SCENES_DIR/$scene/scene.xml" --backend cpu --integrator nee \
        --paths 32 --width 256 --height 256 --out "$tmp/r.exr" --png "$tmp/r.png" | grep -E '^kernel time')
      echo "round $r $entry $scene $line" | tee -a "$tmp/runs"
    done
  done
done
python3 - "$tmp/runs" <<'EOF'
import re, statistics, sys
runs = {}
for line in open(sys.argv[1]):
    _, _, entry, scene, rest = line.split(" ", 4)
    total = float(re.search(r"kernel time\s+([\d.]+) ms", rest).group(1))
    stages = dict((k, float(v)) for k, v in re.findall(r"(\w+) ([\d.]+)", rest.split(":", 1)[1]))
    t, e, sh = stages["traverse"], stages["extend"], stages["shadow"]
    runs.setdefault((scene, entry), []).append((total, t, e, sh, e / (t + sh)))
print("medians, ms")
for (scene, entry), v in sorted(runs.items()):
    med = [statistics.median(x[i] for x in v) for i in range(5)]
    print(f"{scene:14} {entry:28} n={len(v)} total={med[0]:.0f} traverse={med[1]:.0f} extend={med[2]:.0f} shadow={med[3]:.0f} extend/(traverse+shadow)={med[4]:.3f}")
EOF
