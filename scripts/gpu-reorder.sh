#!/usr/bin/env bash
# Ray reordering end to end (BENCHMARKS.md) on a GPU machine,
# through the device tool, from the repository root: `cohort render --reorder K` for K = 0
# (off), 1 (every iteration) and 4, with the paper's configurations normal, warp, block_256
# and grid, on the four paper scenes, then K = 0 and 1 on the shared scenes. paths/s per
# kernel second (the sort's time included) and the traversal's rays/s.
# Needs gpu-pack/cohort-new.xz (this commit's release binary) and
# gpu-pack/shared-scenes.tar.xz (../shared/scenes packed). Results: $OUT/reorder.log and
# $OUT/results.tgz (stats JSON, nvidia-smi clocks).
set -uo pipefail
OUT="${OUT:?set OUT to the folder for the results (the device tool sets it)}"
for f in cohort-new shared-scenes.tar; do
  [ -f "gpu-pack/$f.xz" ] || { echo "gpu-pack/$f.xz is missing: build the release binary here and xz it into gpu-pack/ (see the header)" >&2; exit 2; }
done
R=$(mktemp -d)
xz -dc gpu-pack/cohort-new.xz > "$R/cohort" && chmod +x "$R/cohort" || exit 1
mkdir -p "$R/shared" && xz -dc gpu-pack/shared-scenes.tar.xz | tar x -C "$R/shared" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"; export CI=true
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv | tee "$R/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 500 > "$R/smi_during.csv" &
smi=$!
render() { # scene algorithm K
  local tag="$(basename "$(dirname "$1")")_$(basename "$1" .xml)_$2_$3"
  "$R/cohort" render --scene "$1" --backend vulkan --width 1024 --height 1024 --time "${TIME:-2}" \
    --algorithm "$2" --reorder "$3" --out "$R/r.exr" --png "$R/r.png" --stats "$R/s_$tag.json" 2>&1 |
    grep -E "^(paths/s|rays/s|kernel time)|rror" | tr -s ' ' | paste -sd ';' | sed "s|^|$1 $2 reorder=$3: |"
}
for s in confroom sponza fairyforest stanford; do
  for a in normal warp block_256 grid; do
    for k in 0 1 4; do render "$s" "$a" "$k"; done
  done
done 2>&1 | tee "$R/reorder.log"
for s in "$R/shared/cornell-box/scene.xml" "$R/shared/stanford-like/scene.xml"; do
  for k in 0 1 0 1; do render "$s" normal "$k"; done
done 2>&1 | tee -a "$R/reorder.log"
kill $smi
nvidia-smi --query-gpu=clocks.sm,clocks.max.sm --format=csv | tee -a "$R/gpu.txt"
cp "$R/reorder.log" "$OUT/"
rm -f "$R/r.exr" "$R/r.png" "$R/cohort"; rm -rf "$R/shared"
tar czf "$OUT/results.tgz" -C "$R" .
