#!/usr/bin/env bash
# On a GPU machine (through the device tool): kernel_bench on the embedded scenes
# ($SCENES, default confroom,sponza) with the GPU clocks logged beside it. Binaries from
# scripts/build-gpu-bins.sh in bin-gpu/ (or $B). Results: BENCHMARKS.md, docs/results/traversal_cw/.
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-bin-gpu}"
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$OUT/smi_before.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 200 > "$OUT/smi_during.csv" &
smi=$!
$B/kernel_bench "${SCENES:-confroom,sponza}" vulkan 2>&1 | tee "$OUT/kernel_bench.txt"
kill $smi
