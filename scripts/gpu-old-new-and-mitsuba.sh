#!/usr/bin/env bash
# Old vs new `cohort render` (gpu-pack/cohort-old, gpu-pack/cohort-new, xz-packed) on one
# machine in one run, alternating, two rounds; then Mitsuba's render test at its budget on
# wgpu, Vulkan and the CPU (gpu-pack/mitsuba_reference). Writes under $OUT. Run through the
# device tool from the repository root (BENCHMARKS.md, 2026-11-26, e2cfea3 and f8a0627).
set -uo pipefail
for f in cohort-old cohort-new mitsuba_reference; do
  [ -f "gpu-pack/$f.xz" ] || { echo "gpu-pack/$f.xz is missing: build it here (release) and xz it first (BENCHMARKS.md, 2026-11-26, e2cfea3 and f8a0627)" >&2; exit 2; }
done
OUT="${OUT:?set OUT to the folder for the results (the device tool sets it)}"
scripts/unpack-bins.sh gpu-pack || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"; export CI=true
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
for r in 1 2; do for v in old new; do for s in cornell confroom; do for be in vulkan wgpu; do
  echo "== round $r $v $s $be"
  gpu-pack/cohort-$v render --scene $s --backend $be --width 1024 --height 1024 --time 2 \
    --out "$OUT/r.exr" --png "$OUT/r.png" --stats "$OUT/s_${r}_${v}_${s}_${be}.json" 2>&1 | grep -vE "^\s*$" | tail -4
done; done; done; done 2>&1 | tee "$OUT/render.log"
nvidia-smi --query-gpu=clocks.sm,clocks.max.sm --format=csv | tee -a "$OUT/gpu.txt"
rm -f "$OUT/r.exr" "$OUT/r.png"; (cd "$OUT" && tar czf stats.tgz s_*.json && rm -f s_*.json)
(cd render && CARGO_MANIFEST_DIR=$PWD timeout 300 ../gpu-pack/mitsuba_reference --test-threads 8 --nocapture 2>&1 \
  | grep -E "paths per pixel|panicked|test result|FAILED") > "$OUT/mref.log"
tail -3 "$OUT/mref.log"
