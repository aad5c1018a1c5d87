#!/usr/bin/env bash
# The CPU backend against the software Vulkan driver on the same cores: the
# README's first command on each, alternated $ROUNDS times (default 3), paths/s per run.
# Usage: scripts/cpu-vs-software.sh [extra render options]. Builds the release binary
# first unless $BIN names one.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked -p cohort-cli
  BIN=target/release/cohort
fi
ROUNDS="${ROUNDS:-3}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
for r in $(seq "$ROUNDS"); do
  for backend in cpu vulkan; do
    # A failed render is reported with its last lines, not dropped by the filter below.
    if ! out=$("$BIN" render --width 256 --height 256 --paths 32 --backend "$backend" \
      --out "$tmp/$backend.exr" --png "$tmp/$backend.png" "$@" 2>&1); then
      echo "round $r $backend: the render failed:"
      printf '%s\n' "$out" | tail -n 5
      failed=1
      continue
    fi
    line=$(printf '%s\n' "$out" | grep -E '^(paths/s|device)' | tr -s ' ' | paste -sd ';')
    echo "round $r $backend: $line"
  done
done
exit "$failed"
