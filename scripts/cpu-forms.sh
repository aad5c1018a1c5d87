#!/usr/bin/env bash
# The CPU backend's two forms of each kernel, alternated in one run: host forms only
# (COHORT_CPU_SIMD=host), vector forms wherever a kernel has one (=vector) and the default
# (each kernel's faster form, measured). Renders the README's scene (or $SCENE, a name or a
# Mitsuba XML file) at 256x256 with 32 paths per pixel, $ROUNDS rounds (default 3), after
# one run that fills the vector forms' object cache, and checks that every form gives the
# same image bit for bit. Builds the release binary unless $BIN names one.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${ROUNDS:-3}"
SCENE="${SCENE:-cornell}"
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked -p cohort-cli
  BIN=target/release/cohort
fi
BIN=$(realpath "$BIN")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ); commit $(git rev-parse --short HEAD)"
# Renders run in the temporary folder (their PNGs go beside their EXRs there).
[ -f "$SCENE" ] && SCENE=$(realpath "$SCENE")
render() {
  (cd "$out" && COHORT_CPU_SIMD="$1" COHORT_CPU_SIMD_LOG=1 "$BIN" render --backend cpu --scene "$SCENE" \
    --width 256 --height 256 --paths 32 --out "$out/$1.exr" 2>&1)
}
render vector >/dev/null
for r in $(seq "$ROUNDS"); do
  for forms in host measured vector; do
    start=$(date +%s.%N)
    log=$(render "$forms")
    end=$(date +%s.%N)
    echo "round $r $forms: $(grep '^kernel time' <<<"$log"); process $(echo "$end - $start" | bc) s"
    grep 'runs its' <<<"$log" | sed "s/^/  /" || true
  done
done
for forms in measured vector; do
  "$BIN" compare --tolerance 0 "$out/$forms.exr" "$out/host.exr" | tail -n 1 | sed "s/^/$forms against host: /"
done
