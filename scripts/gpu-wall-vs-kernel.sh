#!/usr/bin/env bash
# Render wall time against kernel time for the paper's configurations (normal, warp,
# block_256, grid, and grid with group roulette), at 128x128 (1024 paths per pixel) and
# 1024x1024 (2 s of kernel time), on the Cornell box, for `$B/cohort-old` and `$B/cohort`
# alternated. Usage on the device: OUT=$OUT B=gpu-bin scripts/gpu-wall-vs-kernel.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-gpu-bin}"
mkdir -p "$OUT"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv
for size in 128 1024; do
  budget="--paths 1024"; [ "$size" = 1024 ] && budget="--time 2"
  for cfg in "normal" "warp" "block_256" "grid" "grid --rr group"; do
    for bin in cohort-old cohort; do
      echo "== $size $cfg $bin"
      "$B/$bin" render --scene "${SCENE:-cornell}" --backend vulkan --width $size --height $size $budget \
        --algorithm $cfg --out "$OUT/r.exr" --png "$OUT/r.png" 2>&1 | grep -E "^kernel time|^paths/s|^wall|^mean"
    done
  done
done 2>&1 | tee "$OUT/wall.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
nvidia-smi --query-gpu=clocks.sm --format=csv
