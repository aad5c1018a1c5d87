#!/usr/bin/env bash
# Startup and whole-process time with warm caches, `$B/cohort-base` (before the device
# opened beside the scene load) against `$B/cohort`, alternated, ROUNDS rounds: the
# embedded stanford scan at 512x512 (16 paths) and the README's first command (cornell,
# 256x256, 32 paths). Each binary renders once untimed first, so Cohort's pipeline cache
# and the driver's are warm. `BINS` names other binaries of `$B` to alternate (default
# `cohort-base cohort`). Usage on the device: OUT=$OUT B=gpu-pack2 scripts/gpu-startup.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
B="${B:-gpu-pack2}"; ROUNDS="${ROUNDS:-3}"; BINS="${BINS:-cohort-base cohort}"
scripts/unpack-bins.sh "$B" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv
run() { # bin scene size paths
  local start end
  start=$EPOCHREALTIME
  "$B/$1" render --backend vulkan --scene "$2" --width "$3" --height "$3" --paths "$4" \
    --out "$OUT/r.exr" --png "$OUT/r.png" 2>&1 | grep -E "^startup|^wall"
  end=$EPOCHREALTIME
  awk -v a="$start" -v b="$end" 'BEGIN { printf "process %.3f s\n", b - a }'
}
for bin in $BINS; do run $bin stanford 512 16 > /dev/null; run $bin cornell 256 32 > /dev/null; done
for r in $(seq "$ROUNDS"); do
  for bin in $BINS; do
    echo "== round $r $bin stanford 512"; run $bin stanford 512 16
    echo "== round $r $bin cornell 256 (README)"; run $bin cornell 256 32
  done
done 2>&1 | tee "$OUT/startup.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
