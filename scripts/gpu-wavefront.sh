#!/usr/bin/env bash
# The wavefront sized to the device against one slot per pixel, in one run on one GPU:
# `$B/cohort` with its default wavefront and with `--wavefront 1` (one copy of the image,
# what every render did before), and `$B/cohort-base` (the build before the wavefront) as a
# check that `--wavefront 1` is the old renderer. Cornell box (embedded) and stanford-like
# (`$SCENES/stanford-like/scene.xml`) at 128, 256, 512 and 1024 square, 2 s of kernel time
# each; then every paper configuration at 128 and 1024 for render wall against kernel time.
# Usage on the device: OUT=$OUT B=gpu-pack2 scripts/gpu-wavefront.sh
# (the binaries xz-packed in $B, as scripts/build-gpu-bins.sh leaves them).
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-gpu-pack2}"
SCENES="${SCENES:-render/tests/scenes}"
mkdir -p "$OUT"
scripts/unpack-bins.sh "$B" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
export COHORT_VK_VALIDATION=0
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$OUT/gpu.txt"
run() { # label bin args...
  local label=$1 bin=$2; shift 2
  echo "== $label"
  "$B/$bin" render --backend vulkan --out "$OUT/r.exr" --png "$OUT/r.png" --stats "$OUT/$label.json" "$@" 2>&1 \
    | grep -E "^paths/pixel|^kernel time|^paths/s|^wall|^mean|rror"
}
for scene in cornell stanford-like; do
  arg="--scene cornell"; [ "$scene" = cornell ] || arg="--scene $SCENES/$scene/scene.xml"
  for size in 128 256 512 1024; do
    for v in base one auto; do
      case $v in
        base) bin=cohort-base; extra="" ;;
        one) bin=cohort; extra="--wavefront 1" ;;
        auto) bin=cohort; extra="" ;;
      esac
      run "${scene}_${size}_$v" $bin $arg --width $size --height $size --time 2 $extra
    done
  done
done 2>&1 | tee "$OUT/sizes.log"
for size in 128 1024; do
  for cfg in "normal" "warp" "block_256" "grid" "grid --rr group"; do
    for v in one auto; do
      extra=""; [ $v = one ] && extra="--wavefront 1"
      run "cfg_${size}_${cfg// /_}_$v" cohort --scene cornell --width $size --height $size --time 2 --algorithm $cfg $extra
    done
  done
done 2>&1 | tee "$OUT/configs.log"
nvidia-smi --query-gpu=clocks.sm --format=csv | tee -a "$OUT/gpu.txt"
rm -f "$OUT/r.exr" "$OUT/r.png"
python3 - "$OUT" <<'PY' | tee "$OUT/table.md"
import json, glob, os, sys
out = sys.argv[1]
print("| run | slots | paths/pixel | kernel ms | paths/s (M) | wall s | wall/kernel |")
print("|---|---|---|---|---|---|---|")
for f in sorted(glob.glob(os.path.join(out, "*.json"))):
    s = json.load(open(f))
    k = s["kernel_ms"]["total"]
    print(f"| {os.path.basename(f)[:-5]} | {s.get('slots', '-')} | {s['paths_per_pixel']:.1f} | {k:.0f} | "
          f"{s['paths_per_second'] / 1e6:.1f} | {s['wall_s']:.2f} | {s['wall_s'] * 1000 / k:.3f} |")
PY
