#!/usr/bin/env bash
# The paper's experiments on the GPU machine (through the device tool): a `cohort
# figures` sweep over the four embedded paper scenes at 1024x1024, with a per-point
# kernel-time budget that fits one device call. Packs the CSV and plots into
# $OUT/figures.tgz (the reference EXRs stay behind).
#
# The points of each (scene, D, column, N) group, `normal` included, are measured
# round-robin in SLICES slices (docs/FIGURES.md): the driver lowers the GPU's clocks when
# the host works between points, and this gives every configuration of a group about the
# same mix of clocks. Compare within a group (paths_per_s_vs_normal, rms_at_1spp, or
# against the `normal` row with the same group_n); absolute paths/s still follows the
# clocks. Defaults: 4 scenes x 2 D x 3 columns x 5 N x 6 points x 0.2 s = 144 s of kernel
# time, plus 4 x 4 s of references. bin-gpu/cohort must be built from a source that has
# --slices (scripts/build-gpu-bins.sh).
set -uo pipefail
OUT="${OUT:-./gpu-out}"
mkdir -p "$OUT/fig"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
# `timeout` keeps the packing below alive when a sweep outgrows the device call: the CSV
# is rewritten after every group, so what was measured comes back.
timeout ${LIMIT:-540} bin-gpu/cohort figures --backend vulkan --scenes ${SCENES:-confroom,fairyforest,sponza,stanford} \
  --configs ${CONFIGS:-normal,warp,block_256,block_512,block_1024,grid} --columns ${COLUMNS:-path,rr,rr-no} \
  --interleave ${INTERLEAVE:-5} --n ${NS:-4,16,64,250,1000} --time ${POINT_SECONDS:-0.2} --reference-time ${REF_SECONDS:-4} \
  --slices ${SLICES:-8} --integrator ${INTEGRATOR:-path} --out-dir "$OUT/fig" 2>&1 | grep -v "^\s*$" > "$OUT/fig/figures.log"
tail -${LOG_LINES:-40} "$OUT/fig/figures.log"
(cd "$OUT/fig" && tar czf ../figures${TAG:-}.tgz *.csv *.png *.svg *.log) && rm -rf "$OUT/fig"
