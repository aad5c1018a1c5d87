#!/usr/bin/env bash
# The traversal work's experiments on a GPU machine, through the device tool, from the
# repository root (BENCHMARKS.md, 2026-11-27, d2bc83f and 807cf8c). Old and new release
# binaries alternate in one run:
#   1. `traversal_variants` ($SCENES): traverse8 against any-hit, dynamic fetch and
#      sorted rays, old binary first and last;
#   2. `cohort render` on the four paper scenes and the shared scenes, two rounds;
#   3. `kernel_bench` (new) on confroom: the standard traversal table.
# Binaries, xz-packed in gpu-pack/: traversal_variants{,-old}, cohort-{old,new},
# kernel_bench; the shared scenes as gpu-pack/shared-scenes.tar.xz. Results: one archive,
# $OUT/results.tgz (the device tool brings back a few files only).
set -uo pipefail
OUT="${OUT:?set OUT to the folder for the results (the device tool sets it)}"
for f in traversal_variants traversal_variants-old cohort-old cohort-new kernel_bench shared-scenes.tar; do
  [ -f "gpu-pack/$f.xz" ] || { echo "gpu-pack/$f.xz is missing: build the release binaries here, xz them into gpu-pack/ and pack ../shared/scenes as shared-scenes.tar.xz first (BENCHMARKS.md, 2026-11-27, d2bc83f and 807cf8c)" >&2; exit 2; }
done
R=$(mktemp -d)
scripts/unpack-bins.sh gpu-pack || exit 1
mkdir -p "$R/shared" && tar xf gpu-pack/shared-scenes.tar -C "$R/shared"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"; export CI=true
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$R/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 250 > "$R/smi_during.csv" &
smi=$!
for v in -old "" -old ""; do
  echo "== traversal_variants$v"
  gpu-pack/traversal_variants$v "${SCENES:-confroom,sponza,fairyforest,stanford}" vulkan
done 2>&1 | tee "$R/variants.log"
for r in 1 2; do for v in old new; do
  for s in cornell confroom sponza fairyforest stanford "$R/shared/cornell-box/scene.xml" "$R/shared/stanford-like/scene.xml"; do
    echo "== round $r $v $(basename $(dirname $s))/$(basename $s)"
    gpu-pack/cohort-$v render --scene "$s" --backend vulkan --width 1024 --height 1024 --time 2 \
      --out "$R/r.exr" --png "$R/r.png" --stats "$R/s_${r}_${v}_$(echo $s | tr / _).json" 2>&1 | grep -E "paths/s|rays/s|kernel time|error" | tail -3
  done
done; done 2>&1 | tee "$R/render.log"
gpu-pack/kernel_bench confroom vulkan 2>&1 | tee "$R/kernel_bench.log"
kill $smi
nvidia-smi --query-gpu=clocks.sm,clocks.max.sm --format=csv | tee -a "$R/gpu.txt"
rm -f "$R/r.exr" "$R/r.png"; rm -rf "$R/shared"
tar czf "$OUT/results.tgz" -C "$R" .
