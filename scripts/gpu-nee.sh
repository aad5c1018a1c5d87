#!/usr/bin/env bash
# GPU run for next-event estimation and the never-waiting loop: GPU suites that
# cover light sampling, kernel_bench (traversal after the semantics changes), and renders
# of the shared scenes with both integrators, logging nvidia-smi clocks beside them.
# Expects bin-gpu/ (release binaries) and shared-scenes/ (a copy of ../shared/scenes).
set -uo pipefail
OUT="${OUT:-./gpu-out}"
mkdir -p "$OUT"
B=bin-gpu
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export CI=true COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu,clocks_event_reasons.active --format=csv -lms 250 > "$OUT/clocks.csv" &
SMI=$!
# The test binaries look for the shared scenes where they were built.
mkdir -p /work/main/render /work/main/tests /work/shared && ln -sfn "$PWD/shared-scenes" /work/shared/scenes
{
for t in ${SUITES:-nee render difftest conformance_numeric}; do
  echo "== $t"; (cd /work/main/render && "$OLDPWD/$B/$t" --test-threads 1 2>&1 | grep -E "^test |panicked|differ|test result" | tail -15)
done
} 2>&1 | tee "$OUT/tests.log"
echo "== kernel bench"; $B/kernel_bench confroom vulkan 2>&1 | tee "$OUT/kernel_bench.txt"
for s in cornell-box stanford-like; do
  for i in nee path; do
    for budget in "--paths 256" "--time 1"; do
      echo "== render $s $i $budget"
      /usr/bin/time -f "process wall %e s" $B/cohort render --scene shared-scenes/$s/scene.xml --backend vulkan --width 1024 --height 1024 $budget --integrator $i \
        --out "$OUT/r.exr" --png "$OUT/${s}_$i.png" --stats "$OUT/r_${s}_${i}_${budget// /}.json" 2>&1 | grep -E "paths/pixel|kernel time|paths/s|rays/s|^wall|process wall|mean"
    done
  done
done 2>&1 | tee "$OUT/render.log"
rm -f "$OUT/r.exr"
for s in cornell confroom fairyforest sponza stanford; do
  echo "== render $s nee"; $B/cohort render --scene $s --backend vulkan --width 1024 --height 1024 --time 1 --integrator nee --out "$OUT/r.exr" --png "$OUT/r.png" 2>&1 | grep -E "kernel time|paths/s|^wall"
done 2>&1 | tee "$OUT/render_embedded.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
kill $SMI
(cd "$OUT" && tar czf stats.tgz r_*.json clocks.csv *.png && rm -f r_*.json clocks.csv *.png)
