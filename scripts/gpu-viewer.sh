#!/usr/bin/env bash
# The viewer's paths/s at 256x256 against `cohort render`'s at 256x256 and 1024x1024, on the
# same GPU, alternated ROUNDS rounds, per scene. The viewer runs under Xvfb (the device has
# no display) driven by a script; its `notify` line reports paths per second of kernel time,
# the figure its panel shows. Needs Xvfb and the X client libraries. A device without them
# gets them as .debs downloaded here (Debian 12) and extracted there into / first
# (`for f in gpu-x/*.deb; do dpkg -x $f /; done`):
#   apt-get download xvfb x11-xkb-utils xkb-data xserver-common libaudit1 libbrotli1 libbsd0 \
#     libcap-ng0 libfontenc1 libfreetype6 libmd0 libpixman-1-0 libpng16-16 libunwind8 libx11-6 \
#     libx11-data libx11-xcb1 libxau6 libxcb-xkb1 libxcb1 libxcursor1 libxdmcp6 libxext6 \
#     libxfixes3 libxfont2 libxi6 libxkbcommon-x11-0 libxkbcommon0 libxkbfile1 libxrandr2 \
#     libxrender1 libxshmfence1
# Usage on the device: OUT=$OUT B=gpu-s scripts/gpu-viewer.sh
set -uo pipefail
OUT="${OUT:-./gpu-out}"; mkdir -p "$OUT"
B="${B:-gpu-s}"; ROUNDS="${ROUNDS:-2}"
SCENES="${SCENES:-render/tests/scenes/cornell-box/scene.xml render/tests/scenes/stanford-like/scene.xml}"
PATHS="${PATHS:-4096}"; BIG_PATHS="${BIG_PATHS:-256}"; BACKEND="${BACKEND:-vulkan}"
scripts/unpack-bins.sh "$B" || exit 1
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv 2>/dev/null

# Xvfb picks a free display and writes its number to fd 3; its built-in fonts spare a
# device the font packages.
exec 3< <(Xvfb -displayfd 1 -screen 0 1024x768x24 -nolisten tcp -fp built-ins 2>"$OUT/xvfb.err")
xvfb=$!; trap 'kill $xvfb 2>/dev/null' EXIT
read -r -t 20 n <&3 || { echo "Xvfb did not start:"; cat "$OUT/xvfb.err"; exit 1; }
export DISPLAY=":$n"

rate() { # stats.json -> M paths/s per kernel second
  python3 -c "import json,sys; print('%.1f' % (json.load(open(sys.argv[1]))['paths_per_second'] / 1e6))" "$1"
}
for r in $(seq "$ROUNDS"); do
  for s in $SCENES; do
    name=$(basename "$(dirname "$s")")
    printf 'wait-paths %s\nnotify done\nquit\n' "$PATHS" > "$OUT/view.script"
    v=$(timeout 300 "$B/cohort" view --backend "$BACKEND" --scene "$s" --width 256 --height 256 \
      --paths "$PATHS" --script "$OUT/view.script" 2>"$OUT/view-$name.err" \
      | python3 -c "import json,sys; print('%.1f' % (json.loads(sys.stdin.readlines()[-1])['paths_per_second'][0] / 1e6))")
    "$B/cohort" render --backend "$BACKEND" --scene "$s" --width 256 --height 256 --paths "$PATHS" \
      --out "$OUT/r.exr" --png "$OUT/r.png" --stats "$OUT/r256.json" >/dev/null 2>&1
    "$B/cohort" render --backend "$BACKEND" --scene "$s" --width 1024 --height 1024 --paths "$BIG_PATHS" \
      --out "$OUT/r.exr" --png "$OUT/r.png" --stats "$OUT/r1024.json" >/dev/null 2>&1
    echo "round $r $name: view 256 ${v:-failed} M paths/s, render 256 $(rate "$OUT/r256.json") M, render 1024 $(rate "$OUT/r1024.json") M"
    [ -n "$v" ] || tail -5 "$OUT/view-$name.err"
  done
done 2>&1 | tee "$OUT/viewer.log"
rm -f "$OUT/r.exr" "$OUT/r.png"
