#!/usr/bin/env bash
# Two `cohort` builds against each other on the GPU machine, alternated in one run so that
# clocks and neighbours treat them alike: `$B/cohort-old` (the baseline) and `$B/cohort`,
# on the embedded scenes, ROUNDS rounds, nvidia-smi clocks logged beside. Then, where
# `$B/mitsuba_reference` is there, Mitsuba's render test (scenes and references travel with
# the repository). Usage on the device: OUT=$OUT B=gpu-pack scripts/gpu-compare.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-bin-gpu}"
scripts/unpack-bins.sh "$B" || exit 1
mkdir -p "$OUT"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export CI=true COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu --format=csv -lms 500 > "$OUT/clocks.csv" &
SMI=$!
for round in $(seq 1 "${ROUNDS:-2}"); do
  for s in ${SCENES:-cornell confroom stanford}; do
    for bin in cohort-old cohort; do
      echo "== round $round $s $bin"
      "$B/$bin" render --scene "$s" --backend vulkan --width 1024 --height 1024 --time "${SECONDS_EACH:-2}" \
        ${RENDER_ARGS:-} --out "$OUT/r.exr" 2>&1 | grep -E "kernel time|paths/s|^wall|extend|traverse|shadow"
    done
  done
done 2>&1 | tee "$OUT/compare.log"
rm -f "$OUT/r.exr"
if [ -x "$B/mitsuba_reference" ]; then
  echo "== mitsuba_reference"
  (cd render && CARGO_MANIFEST_DIR=$PWD "../$B/mitsuba_reference" --test-threads 1 --nocapture 2>&1 |
    grep -E "pixel channels pass \(|panicked|^test .*FAILED|test result") | tee "$OUT/mitsuba_reference.log"
fi
kill $SMI
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv | tee -a "$OUT/gpu.txt"
