#!/usr/bin/env bash
# Two `cohort render` builds against each other under a paths budget at several image sizes
# on one GPU, alternated in one run (ROUNDS rounds) with clocks logged beside: `$B/cohort-old`
# (the baseline) and `$B/cohort` (plain or .xz), on the embedded scenes. Each size renders
# about 67 M paths (4096 per pixel at 128 square, 64 at 1024), so that the wavefront's last
# iterations, where slots finish, are part of what is timed. The first round's images of
# the two builds are compared bit for bit. On the device:
#   OUT=$OUT B=gpu-b scripts/gpu-paths-old-new.sh
set -uo pipefail
OUT="${OUT:?set OUT to the folder for the results (the device tool sets it)}"
B="${B:-gpu-b}"
scripts/unpack-bins.sh "$B" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"; export CI=true
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu --format=csv -lms 500 > "$OUT/clocks.csv" &
SMI=$!
for round in $(seq 1 "${ROUNDS:-3}"); do
  for size in ${SIZES:-128 256 1024}; do
    paths=$((67108864 / (size * size)))
    for s in ${SCENES:-cornell stanford}; do
      for bin in cohort-old cohort; do
        echo "== round $round $s ${size}x$size $paths paths $bin"
        "$B/$bin" render --scene "$s" --backend vulkan --width "$size" --height "$size" --paths "$paths" \
          ${RENDER_ARGS:-} --out "$OUT/r-$bin.exr" --png "$OUT/r-$bin.png" 2>&1 | grep -E "kernel time|paths/s|^wall|iterations"
      done
      if [ "$round" = 1 ]; then
        "$B/cohort" compare "$OUT/r-cohort-old.exr" "$OUT/r-cohort.exr" --tolerance 0 2>&1 | tail -1
      fi
    done
  done
done 2>&1 | tee "$OUT/compare.log"
rm -f "$OUT"/r-*.exr "$OUT"/r-*.png
kill $SMI
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv | tee -a "$OUT/gpu.txt"
