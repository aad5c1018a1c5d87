#!/usr/bin/env bash
# The designs of shading specialised on the scene, against each other on the GPU machine,
# alternated in one run: one `extend` built with the scene's kinds (`--shading kernel`),
# material queues (`--shading queues`, one `extend` per kind over its queue) and the
# default, `auto` (both measured on the render, the faster kept); $DESIGNS picks. Warm:
# paths/s and kernel time by stage at 1024x1024 for $SECONDS_EACH seconds of kernel time,
# $ROUNDS rounds, on the embedded scenes of $SCENES and the Mitsuba render-test scenes of
# $MITSUBA (several kinds each). Cold: time to the first iteration with empty caches (a
# fresh COHORT_CACHE_DIR, the driver's shader cache off), 256x256, one path per pixel.
# COLD=0 skips the cold starts. nvidia-smi clocks logged beside. Needs `$B/cohort` (or `$B/cohort.xz`) built for the
# device (scripts/build-gpu-bins.sh). Usage on the device: OUT=$OUT B=gpu-bin
# scripts/gpu-shading-designs.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-bin-gpu}"
mkdir -p "$OUT"
if [ ! -x "$B/cohort" ]; then
  [ -f "$B/cohort.xz" ] || { echo "neither $B/cohort nor $B/cohort.xz: build it with scripts/build-gpu-bins.sh" >&2; exit 2; }
  xz -dc "$B/cohort.xz" > "$B/cohort" && chmod +x "$B/cohort" || exit 1
fi
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
M=render/tests/scenes/mitsuba
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu --format=csv -lms 500 > "$OUT/clocks.csv" &
SMI=$!
scene_arg() { case "$1" in */*) echo "$1" ;; *) [ -f "$M/$1.xml" ] && echo "$M/$1.xml" || echo "$1" ;; esac; }
{
  for round in $(seq 1 "${ROUNDS:-2}"); do
    for s in ${SCENES:-cornell confroom stanford sponza} ${MITSUBA:-blendbsdf dielectric_sheets principled conductor roughplastic}; do
      for d in ${DESIGNS:-kernel queues auto}; do
        echo "== warm round $round $s $d"
        "$B/cohort" render --scene "$(scene_arg "$s")" --shading "$d" --backend vulkan \
          --width 1024 --height 1024 --time "${SECONDS_EACH:-2}" --out "$OUT/r.exr" --png "$OUT/r.png" 2>&1 |
          grep -E "kernel time|paths/s|^wall|^shading|^error|panicked"
      done
    done
  done
} 2>&1 | tee "$OUT/warm.log"
[ "${COLD:-1}" = 1 ] && {
  for s in ${SCENES:-cornell confroom stanford sponza} ${MITSUBA:-blendbsdf dielectric_sheets principled conductor roughplastic}; do
    for d in ${DESIGNS:-kernel queues auto}; do
      echo "== cold $s $d"
      c=$(mktemp -d)
      t0=$(date +%s%N)
      __GL_SHADER_DISK_CACHE=0 COHORT_CACHE_DIR="$c" "$B/cohort" render --scene "$(scene_arg "$s")" \
        --shading "$d" --backend vulkan --width 256 --height 256 --paths 1 --out "$c/r.exr" \
        --png "$c/r.png" 2>&1 | grep -E "^startup|^error|panicked"
      echo "   process $(( ($(date +%s%N) - t0) / 1000000 )) ms"
      rm -rf "$c"
    done
  done
} 2>&1 | tee "$OUT/cold.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
kill $SMI
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv | tee -a "$OUT/gpu.txt"
