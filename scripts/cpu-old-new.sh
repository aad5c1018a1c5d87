#!/usr/bin/env bash
# Two builds of `cohort` on the CPU backend, alternated: the README's first command under
# each paper configuration (normal, warp, block_256, grid), $ROUNDS times (default 3),
# kernel paths/s per run. Usage: scripts/cpu-old-new.sh OLD_BIN NEW_BIN [render options].
set -euo pipefail
cd "$(dirname "$0")/.."
old="$1"; new="$2"; shift 2
ROUNDS="${ROUNDS:-3}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ)"
for r in $(seq "$ROUNDS"); do
  for algorithm in normal warp block_256 grid; do
    for which in old new; do
      bin=$old; [ "$which" = new ] && bin=$new
      rate=$("$bin" render --width 256 --height 256 --paths 32 --backend cpu --algorithm "$algorithm" \
        --out "$tmp/c.exr" --png "$tmp/c.png" "$@" | grep -E '^paths/s' | tr -s ' ' | cut -d' ' -f2)
      echo "round $r $algorithm $which $rate"
    done
  done
done
