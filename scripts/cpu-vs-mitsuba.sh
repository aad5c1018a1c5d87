#!/usr/bin/env bash
# The CPU backend against Mitsuba 3's vectorised LLVM variant (`llvm_ad_rgb`) on the same
# cores and scene files: time to Mitsuba's error at 32 spp, 256x256, on cornell-box and
# stanford-like (scripts/equal_time.py does the rendering and the arithmetic).
# Installs Mitsuba 3.9.1 into a virtual environment ($VENV, default target/mitsuba-venv)
# and Debian's libllvm19 when they are missing. Builds the release binary unless $BIN
# names one. Usage: scripts/cpu-vs-mitsuba.sh [SCENES_DIR] (default render/tests/scenes);
# $OUT_DIR (default target/cpu-vs-mitsuba) receives equal_time.{md,csv,png}; $SEEDS
# (e.g. "1 2 3") renders Cohort once per seed, $MITSUBA_SEEDS (e.g. "1,2,3") Mitsuba.
set -euo pipefail
cd "$(dirname "$0")/.."
SCENES="${1:-render/tests/scenes}"
VENV="${VENV:-target/mitsuba-venv}"
OUT_DIR="${OUT_DIR:-target/cpu-vs-mitsuba}"
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c "import mitsuba, numpy, matplotlib" 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q mitsuba==3.9.1 numpy matplotlib
fi
# Mitsuba's LLVM variant needs a libLLVM of version 16 or newer.
llvm=$(ls /usr/lib/x86_64-linux-gnu/libLLVM-19.so /usr/lib/x86_64-linux-gnu/libLLVM.so.19* 2>/dev/null | head -n 1 || true)
if [ -z "$llvm" ]; then
  apt-get install -y -q libllvm19 >/dev/null
  llvm=$(ls /usr/lib/x86_64-linux-gnu/libLLVM.so.19* | head -n 1)
fi
export DRJIT_LIBLLVM_PATH="$llvm"
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked -p cohort-cli
  BIN=target/release/cohort
fi
configs=""
for s in ${SEEDS:-1}; do
  configs="${configs:+$configs;}--backend cpu --integrator nee --seed $s"
done
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ); commit $(git rev-parse --short HEAD)"
"$VENV/bin/python" scripts/equal_time.py --scenes "$SCENES" --cohort "$BIN" \
  --variant llvm_ad_rgb --size 256 --ref-spp 2048 --target-spp 32 \
  --mitsuba-spp 8,16,32,64 --cohort-paths 8,16,32,64,128 \
  --mitsuba-seeds "${MITSUBA_SEEDS:-1}" --cohort-args "$configs" --out "$OUT_DIR"
