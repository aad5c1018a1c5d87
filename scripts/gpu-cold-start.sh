#!/usr/bin/env bash
# Time to the first iteration with empty caches, and paths/s with warm ones, of two `cohort`
# builds on the GPU machine, alternated in one run: `$B/cohort-old` (the baseline) and
# `$B/cohort`. Cold: a fresh COHORT_CACHE_DIR and the NVIDIA driver's shader cache off
# (`__GL_SHADER_DISK_CACHE=0`), 256x256, one path per pixel, for the embedded scenes, the
# Mitsuba scenes of `$S` (default gpu-scenes/, copies of the shared scene files) and the
# Mitsuba render-test scenes named in $MITSUBA. Warm: 1024x1024 for $SECONDS_EACH seconds of
# kernel time on $SCENES, $ROUNDS rounds. nvidia-smi clocks logged beside.
# Usage on the device: OUT=$OUT B=gpu-bin scripts/gpu-cold-start.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-gpu-bin}"
scripts/unpack-bins.sh "$B" || exit 1
S="${S:-gpu-scenes}"
mkdir -p "$OUT"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu --format=csv -lms 500 > "$OUT/clocks.csv" &
SMI=$!
cold() { # bin scene-args...
  local bin=$1; shift
  local c; c=$(mktemp -d)
  local t0; t0=$(date +%s%N)
  __GL_SHADER_DISK_CACHE=0 COHORT_CACHE_DIR="$c" "$B/$bin" render "$@" --backend vulkan \
    --width 256 --height 256 --paths 1 --out "$c/r.exr" --png "$c/r.png" 2>&1 | grep -E "^startup|^error|panicked"
  echo "   process $(( ($(date +%s%N) - t0) / 1000000 )) ms"
  rm -rf "$c"
}
{
  for s in ${EMBEDDED:-cornell confroom fairyforest sponza stanford}; do
    for bin in cohort-old cohort; do echo "== cold $s $bin"; cold "$bin" --scene "$s"; done
  done
  for f in "$S"/*/scene.xml; do
    [ -e "$f" ] || continue
    for bin in cohort-old cohort; do echo "== cold $f $bin"; cold "$bin" --scene "$f"; done
  done
  for m in ${MITSUBA:-principled roughplastic roughdielectric blendbsdf normalmap envmap}; do
    for bin in cohort-old cohort; do
      echo "== cold mitsuba/$m $bin"; cold "$bin" --scene "render/tests/scenes/mitsuba/$m.xml"
    done
  done
} 2>&1 | tee "$OUT/cold.log"
for round in $(seq 1 "${ROUNDS:-2}"); do
  for s in ${SCENES:-cornell confroom stanford sponza}; do
    for bin in cohort-old cohort; do
      echo "== warm round $round $s $bin"
      "$B/$bin" render --scene "$s" --backend vulkan --width 1024 --height 1024 --time "${SECONDS_EACH:-2}" \
        --out "$OUT/r.exr" --png "$OUT/r.png" 2>&1 | grep -E "kernel time|paths/s|^wall|^startup"
    done
  done
done 2>&1 | tee "$OUT/warm.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
kill $SMI
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv | tee -a "$OUT/gpu.txt"
