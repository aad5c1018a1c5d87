#!/usr/bin/env bash
# Runs the GPU suites and benchmarks on a machine with a real GPU, from binaries built
# elsewhere into bin-gpu/ (see scripts/build-gpu-bins.sh). Writes logs and stats under
# $OUT (default ./gpu-out). Used through the device tool; see BENCHMARKS.md.
set -uo pipefail
OUT="${OUT:-./gpu-out}"
mkdir -p "$OUT"
B=bin-gpu
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export CI=true COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv | tee "$OUT/gpu.txt"
{
for t in difftest random_kernels conformance_numeric traversal render nee runtime_dispatch runtime_errors; do
  [ -x "$B/$t" ] || continue
  # The shared scenes do not travel to the GPU machine: run the render tests that need none.
  filter=""; [ "$t" = render ] && filter="backends_agree white_furnace"; [ "$t" = nee ] && filter="white_furnace environment"
  # The runtime's dispatch tests run on parallel threads, as `cargo test` runs them: that
  # is how devices created and destroyed at once deadlocked NVIDIA's driver.
  threads="--test-threads 1"; [ "$t" = runtime_dispatch ] && threads=""
  echo "== $t"; (cd tests && timeout 300 ../$B/$t $threads $filter 2>&1 | grep -E "^test |panicked|differ|test result" | tail -12)
done
# Renderers in flat memory, and Mitsuba's render test at its budget (the scenes and
# references travel with the repository; the binary finds them through CARGO_MANIFEST_DIR).
for t in memory mitsuba_reference; do
  [ -x "$B/$t" ] || continue
  echo "== $t"; (cd render && CARGO_MANIFEST_DIR=$PWD ../$B/$t --test-threads 1 --nocapture 2>&1 | grep -E "resident|pixel channels pass \(|panicked|test result")
done
} 2>&1 | tee "$OUT/tests.log"
echo "== compile times"; $B/compile_times 25 | tee "$OUT/compile_times.md" | tail -3
for be in vulkan wgpu; do
  echo "== kernel bench $be"; $B/kernel_bench confroom $be 2>&1 | tee "$OUT/kernel_bench_$be.txt"
done
# Coherent configurations against normal, same run, one scene per run.
for s in ${COHERENT_SCENES:-confroom}; do
  for cfg in "normal --compact" "warp --compact" "block_256 --compact" "block_512 --compact" "block_1024 --compact" "grid --compact" "warp --rr group " "block_256 --rr group" "warp --in-patch equal-area --compact" "normal" \
      "warp --rr whole --compact" "warp --rr whole " "block_256 --rr whole"; do
    echo "== coherent $s $cfg"
    $B/cohort render --scene $s --backend vulkan --width 1024 --height 1024 --time ${COHERENT_SECONDS:-1} --n 100 --algorithm $cfg \
      --out "$OUT/c.exr" --png "$OUT/c.png" 2>&1 | grep -E "^algorithm|paths/s"
  done
done 2>&1 | tee "$OUT/coherent.log"
rm -f "$OUT/c.exr" "$OUT/c.png"
for be in vulkan wgpu; do
  for s in ${RENDER_SCENES:-cornell confroom fairyforest sponza stanford}; do
    echo "== render $s $be"
    $B/cohort render --scene $s --backend $be --width 1024 --height 1024 --time ${RENDER_SECONDS:-2} \
      --out "$OUT/r.exr" --png "$OUT/r.png" --stats "$OUT/r_${s}_$be.json" 2>&1 | grep -E "paths/pixel|kernel time|paths/s|rays/s"
  done
done 2>&1 | tee "$OUT/render.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
# Few files come back: pack the stats.
(cd "$OUT" && tar czf stats.tgz r_*.json && rm -f r_*.json)
