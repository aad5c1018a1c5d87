#!/usr/bin/env bash
# Runs scripts/equal_time.py on the GPU machine: Mitsuba 3 (cuda_ad_rgb, carried as an
# unpacked, trimmed site folder: see BENCHMARKS.md) and Cohort (bin-gpu/cohort) on the
# shared scenes (carried copy in shared-scenes/), same GPU, same run. Writes to $OUT.
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu,clocks_event_reasons.active --format=csv -lms 500 > "$OUT/clocks_equal_time.csv" &
SMI=$!
python3 scripts/equal_time.py --scenes shared-scenes --cohort bin-gpu/cohort --variant cuda_ad_rgb --size 1024 \
  --ref-spp 4096,2048 --mitsuba-spp 32,64,128,256,512,1024 --cohort-paths 32,64,128,256,512,1024 \
  --cohort-args "--integrator nee --backend vulkan;--integrator nee --backend vulkan ;--integrator path --backend vulkan" \
  --out "$OUT" 2>&1 | tee "$OUT/equal_time.log"
kill $SMI
