#!/usr/bin/env bash
# Prints the ten slowest test binaries of a `cargo test` log (each binary's "finished in"
# time, with the target it ran), slowest first: where CI's time goes.
# Usage: scripts/slowest-tests.sh LOG
set -euo pipefail
log=${1:?usage: scripts/slowest-tests.sh CARGO_TEST_LOG}
echo "ten slowest test binaries (seconds):"
awk '
  /^ *Running / { sub(/^ *Running /, ""); name = $0; next }
  /^ *Doc-tests / { name = "doc-tests " $2; next }
  /^test result:/ && match($0, /finished in [0-9.]+s/) {
    t = substr($0, RSTART + 12, RLENGTH - 13); printf "%10.1f  %s\n", t, name
  }
' "$log" | sort -rn | head -10
