#!/usr/bin/env bash
# The CPU backend's vector forms at several block widths, alternated: kernel time per stage
# (`--stats`) with vector forms forced (COHORT_CPU_SIMD=vector) and COHORT_CPU_SIMD_LANES set.
# Usage: scripts/cpu-widths.sh [render options], e.g.
#   ROUNDS=5 WIDTHS="8 16 32" ALGORITHMS="normal warp" scripts/cpu-widths.sh \
#     --scene render/tests/scenes/cornell-box/scene.xml --integrator nee --width 256 --height 256 --paths 32
# One untimed render per width first fills the object cache ($COHORT_CACHE_DIR, default a
# temporary folder). COHORT_CPU_SIMD_TARGET=x86-64-v3 measures the code of an AVX2 machine.
# Builds the release binary unless $BIN names one. Prints one line per render, then the
# median of each stage per algorithm and width.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${ROUNDS:-3}"
WIDTHS="${WIDTHS:-8 16 32}"
ALGORITHMS="${ALGORITHMS:-normal warp}"
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked -p cohort-cli
  BIN=target/release/cohort
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export COHORT_CACHE_DIR="${COHORT_CACHE_DIR:-$tmp/cache}"
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ); commit $(git rev-parse --short HEAD)"
render() {
  COHORT_CPU_SIMD=vector COHORT_CPU_SIMD_LANES="$1" "$BIN" render --backend cpu --algorithm "$2" \
    "${@:3}" --stats "$tmp/stats.json" --out "$tmp/w.exr" 2>&1
}
for a in $ALGORITHMS; do for w in $WIDTHS; do render "$w" "$a" "$@" >/dev/null; done; done
for r in $(seq "$ROUNDS"); do for a in $ALGORITHMS; do for w in $WIDTHS; do
  echo "$a w=$w $(render "$w" "$a" "$@" | grep -E '^kernel time' | cut -c16-)"
done; done; done | tee "$tmp/log"
python3 - "$tmp/log" <<'PY'
import collections, re, statistics, sys
d = collections.defaultdict(lambda: collections.defaultdict(list))
for line in open(sys.argv[1]):
    m = re.match(r'(\S+) w=(\d+) ([\d.]+) ms: (.*)', line)
    if m:
        k = (m[1], int(m[2]))
        d[k]['total'].append(float(m[3]))
        for part in m[4].split(', '):
            name, v = part.split()
            d[k][name].append(float(v))
print('medians (ms):')
for k in sorted(d):
    print(f'  {k[0]} {k[1]} lanes:', ', '.join(f'{n} {statistics.median(v):.0f}'
          for n, v in d[k].items() if statistics.median(v) > 0))
PY
