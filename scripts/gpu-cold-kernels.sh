#!/usr/bin/env bash
# Time to the first iteration with empty caches (a fresh COHORT_CACHE_DIR, the NVIDIA
# driver's shader cache off) for each shading design (`--shading auto`, `kernel`,
# `queues`), with each pipeline thread's time from `--stats` (`startup_s.kernels`): which
# kernel a cold start waits for. Mitsuba render-test scenes named in $SCENES, 256x256, one
# path per pixel, each build of $BINS in `$B` (default `cohort`) in turn, so that builds
# alternate under the same load. Usage on the device:
# OUT=$OUT B=gpu-s BINS="cohort-old cohort" scripts/gpu-cold-kernels.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
B="${B:-gpu-s}"
SCENES="${SCENES:-blendbsdf_texture blendbsdf principled_textured}"
DESIGNS="${DESIGNS:-auto kernel queues}"
scripts/unpack-bins.sh "$B" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv
for s in $SCENES; do
  for d in $DESIGNS; do
   for bin in ${BINS:-cohort}; do
    c=$(mktemp -d)
    __GL_SHADER_DISK_CACHE=0 COHORT_CACHE_DIR="$c" "$B/$bin" render \
      --scene "render/tests/scenes/mitsuba/$s.xml" --backend vulkan --width 256 --height 256 \
      --paths 1 --shading "$d" --out "$c/r.exr" --png "$c/r.png" --stats "$OUT/cold-$s-$d-$bin.json" 2>&1 |
      grep -E "^startup|^error"
    # The five longest pipeline threads, named without their type parameters.
    python3 -c "
import json, sys
k = json.load(open(sys.argv[1]))['startup_s']['kernels']
longest = sorted(k.items(), key=lambda x: -x[1])[:5]
print('  ' + sys.argv[2] + ':', ', '.join('%s %.2f' % (n.split('___')[0], t) for n, t in longest))
" "$OUT/cold-$s-$d-$bin.json" "$s $d $bin"
    rm -rf "$c"
   done
  done
done 2>&1 | tee "$OUT/cold-kernels.log"
