#!/usr/bin/env bash
# Builds the release binaries that scripts/gpu-run.sh runs on the GPU machine (same
# x86-64, no registry there) into bin-gpu/, stripped so they travel light.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p bin-gpu
# The `cohort` binary explicitly: with `--example`, cargo builds only the examples.
cargo build --release -p cohort-cli --bin cohort
cargo build --release -p cohort-render --example kernel_bench
cargo build --release -p cohort-tests --example compile_times
cp target/release/cohort target/release/examples/kernel_bench target/release/examples/compile_times bin-gpu/
json=$(cargo test --release --no-run -p cohort-tests -p cohort-render -p cohort-runtime --message-format=json 2>/dev/null)
for t in difftest random_kernels traversal render nee compiler_bugs conformance_numeric memory mitsuba_reference; do
  exe=$(echo "$json" | grep -o "\"executable\":\"[^\"]*/$t-[^\"]*\"" | tail -1 | cut -d'"' -f4)
  cp "$exe" "bin-gpu/$t"
done
for t in dispatch errors; do
  exe=$(echo "$json" | grep -o "\"executable\":\"[^\"]*/deps/$t-[^\"]*\"" | tail -1 | cut -d'"' -f4)
  cp "$exe" "bin-gpu/runtime_$t"
done
strip bin-gpu/* || true
du -sh bin-gpu
