#!/usr/bin/env bash
# The paper's experiments on the GPU machine (through the device tool): a `cohort
# figures` sweep over the four embedded paper scenes at 1024x1024, with a per-point
# kernel-time budget that fits one device call. Packs the CSV and plots into
# $OUT/figures.tgz (the reference EXRs stay behind).
set -uo pipefail
OUT="${OUT:-./gpu-out}"
mkdir -p "$OUT/fig"
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
bin-gpu/cohort figures --backend vulkan --scenes ${SCENES:-confroom,fairyforest,sponza,stanford} \
  --n ${NS:-4,16,64,250,1000} --time ${POINT_SECONDS:-0.2} --reference-time ${REF_SECONDS:-4} \
  --out-dir "$OUT/fig" 2>&1 | grep -v "^\s*$" | tail -${LOG_LINES:-40}
(cd "$OUT/fig" && tar czf ../figures.tgz *.csv *.png *.svg) && rm -rf "$OUT/fig"
