#!/usr/bin/env bash
# The CPU backend on a machine's cores (the 16 of a GPU machine, say), several builds
# alternated: cornell (embedded), normal, warp and block_256, then stanford-like with
# light sampling; 512x512, 64 paths. Three warm-up rounds first (vector forms compile once
# a kernel's host form has run as long as LLVM would take). Usage: from a folder holding
# the builds (xz-compressed ones are unpacked; $B names it), with the repository's scenes at
# ../render/tests/scenes: BINS="cohort-old cohort" scripts/cpu-many-cores.sh
set -u
. "$(dirname "$0")/cpu-bins.sh"
SCENE=""
run() { ./$1 render --backend cpu $SCENE --algorithm $2 --width 512 --height 512 --paths 64 --out /tmp/r-$1.exr --stats /tmp/r-$1.json >/dev/null 2>&1; python3 -c "
import json;d=json.load(open('/tmp/r-$1.json'));k=d['kernel_ms'];print('$3 $2 $1', round(d['paths_per_second']/1e6,3), {x:round(v) for x,v in k.items() if v})"; }
for w in 1 2 3; do for a in normal warp block_256; do for b in $BINS; do run $b $a warm$w; done; done; done
for r in 1 2 3; do for a in normal warp block_256; do for b in $BINS; do run $b $a $r; done; done; done
SCENE="--scene ../render/tests/scenes/stanford-like/scene.xml --integrator nee"
for r in w1 w2 1 2 3; do for b in $BINS; do run $b normal stanford-$r; done; done
