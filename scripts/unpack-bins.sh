#!/usr/bin/env bash
# Makes the binaries a GPU script runs ready in folder $1: each `NAME.xz` there (how they
# travel to a device, under its size limit) decompressed beside it, and every file made
# executable. A folder of plain binaries, with no .xz at all, is ready as it is.
# Usage, from another script: scripts/unpack-bins.sh "$B" || exit 1
set -euo pipefail
cd "$1"
shopt -s nullglob
for f in *.xz; do xz -dkf "$f"; done
for f in *; do [ -f "$f" ] && [ "${f%.xz}" = "$f" ] && chmod +x "$f"; done
exit 0
