#!/usr/bin/env bash
# Renders that end while vector forms compile: per case an empty cache, then three renders
# of stanford-like (512x512, 16 paths, light sampling) on the CPU backend, the builds in
# turn, for $LOOP_S seconds (default 300); a failure is a non-zero exit status, with the
# render's last lines (a crash report names the thread and the kernel being compiled).
# Usage, with $B the folder holding the builds (default the current one) and the scenes at
# ../render/tests/scenes: BINS="cohort-old cohort" scripts/cpu-exit-under-compile.sh
set -u
. "$(dirname "$0")/cpu-bins.sh"
S=../render/tests/scenes/stanford-like/scene.xml
fails=0; runs=0; i=0
end=$((SECONDS + ${LOOP_S:-300}))
while [ $SECONDS -lt $end ]; do i=$((i+1)); for b in $BINS; do
  d=$(mktemp -d)
  for k in 1 2 3; do
    COHORT_CACHE_DIR=$d/c ./$b render --backend cpu --scene $S --integrator nee --width 512 --height 512 --paths 16 --out $d/o.exr > $d/log 2>&1; rc=$?
    runs=$((runs+1))
    if [ $rc -ne 0 ]; then fails=$((fails+1)); echo "FAIL case $i $b render $k rc=$rc"; tail -25 $d/log; fi
  done
  echo "case $i $b done"
  rm -rf $d
done; done
echo "runs $runs failures $fails"
