#!/usr/bin/env bash
# Time to Mitsuba 3's error at every image size, on one GPU in one run (the size table of
# BENCHMARKS.md): scripts/equal_time.py at 128, 256, 512 and 1024 square on cornell-box and
# stanford-like, Mitsuba `cuda_ad_rgb` against `cohort render` with its wavefront sized to
# the device and with `--wavefront 1` (one slot per pixel, as before). The ratio is taken at
# Mitsuba's 1024-spp error at 128 and 256, its 256-spp error at 512 and 1024.
# Needs: $B/cohort or $B/cohort.xz (release, stripped), $SITE (Mitsuba 3.9.1 + Dr.Jit cp312 wheels
# unpacked and trimmed to cuda_ad_rgb and the scenes' plugins, as a tar.xz of a `site`
# folder), $SCENES/{cornell-box,stanford-like} (or the scene folders named in $NAMES,
# comma-separated, e.g. NAMES=bunny-box SIZES=512 for the scanned mesh). SEEDS (default 1):
# Cohort's seeds, one configuration each, since one seed's RMS error moves by several percent
# (BENCHMARKS.md, the scanned mesh over five seeds); MITSUBA_SEEDS (default 1, comma-separated):
# Mitsuba's, whose target error is then taken over all of them. On the device:
#   OUT=$OUT B=bin-gpu SITE=gpu-mitsuba/site.tar.xz scripts/gpu-sizes-vs-mitsuba.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
B="${B:-bin-gpu}"; SITE="${SITE:-gpu-mitsuba/site.tar.xz}"; SCENES="${SCENES:-render/tests/scenes}"
# The binary: $B/cohort (e.g. B=bin-gpu from scripts/build-gpu-bins.sh), or $B/cohort.xz.
if [ -f "$B/cohort.xz" ] && [ ! -x "$B/cohort" ]; then
  (cd "$B" && xz -dkf cohort.xz && chmod +x cohort) || exit 1
fi
if [ ! -x "$B/cohort" ]; then
  echo "error: no $B/cohort or $B/cohort.xz: build one with scripts/build-gpu-bins.sh (B=bin-gpu)" >&2
  exit 1
fi
# Mitsuba: $SITE unpacked (pip install --target site mitsuba==3.9.1 drjit, for the device's
# Python, then tar cJf site.tar.xz site), or already importable as `mitsuba` here.
if [ -f "$SITE" ]; then
  tar -C /tmp -xJf "$SITE" || exit 1
elif ! python3 -c "import mitsuba" 2>/dev/null; then
  echo "error: no $SITE and no importable mitsuba: make one as this script's header says" >&2
  exit 1
fi
export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 COHORT_VK_VALIDATION=0
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 1000 > "$OUT/clocks.csv" &
SMI=$!
# One configuration per seed, then one slot per pixel (the first seed).
SEEDS="${SEEDS:-1}"
configs=""
for seed in $SEEDS; do configs="$configs--integrator nee --backend vulkan --seed $seed;"; done
configs="$configs--integrator nee --backend vulkan --wavefront 1 --seed ${SEEDS%% *}"
for size in ${SIZES:-128 256 512 1024}; do
  case $size in
    128) ref=65536,32768; mspp=64,128,256,512,1024,2048; cpaths=64,128,256,512,1024,2048,4096; target=1024 ;;
    256) ref=32768,16384; mspp=64,128,256,512,1024,2048; cpaths=64,128,256,512,1024,2048,4096; target=1024 ;;
    *) ref=4096,2048; mspp=32,64,128,256,512; cpaths=32,64,128,256,512,1024; target=256 ;;
  esac
  python3 scripts/equal_time.py --scenes "$SCENES" --names "${NAMES:-cornell-box,stanford-like}" --cohort "$B/cohort" --variant cuda_ad_rgb --size $size \
    --ref-spp $ref --mitsuba-spp $mspp --cohort-paths $cpaths --target-spp $target \
    --cohort-args "$configs" --mitsuba-seeds "${MITSUBA_SEEDS:-1}" \
    --out "$OUT/size$size" 2>&1 | grep -vE "^\{" | tee "$OUT/size$size.log"
done
kill $SMI
