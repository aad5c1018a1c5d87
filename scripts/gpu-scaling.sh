#!/usr/bin/env bash
# On a GPU machine (through the device tool): where render wall time goes beyond kernel time
# (paths and time budgets, host stages), and one GPU against every GPU of the machine
# (`--devices 0`, `1`, `all`, twice each). Binaries from scripts/build-gpu-bins.sh in bin-gpu/
# (or $B). Writes under $OUT. Results: BENCHMARKS.md, docs/results/multi_gpu/.
set -uo pipefail
OUT="${OUT:-./gpu-out}"
B="${B:-bin-gpu}"
mkdir -p "$OUT"
nvidia-smi --query-gpu=index,name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$OUT/smi.txt"
nvidia-smi --query-gpu=timestamp,index,clocks.sm,utilization.gpu --format=csv -lms 250 > "$OUT/smi_during.csv" &
smi=$!
echo "== host overhead (one device)"
for scene in cornell confroom; do
  for budget in "--paths 256" "--time 1"; do
    $B/cohort render --scene $scene --width 1024 --height 1024 $budget --devices 0 --out /tmp/x.exr --png /tmp/x.png > "$OUT/r.txt" 2>&1
    echo "$scene $budget: $(grep -E '^(paths/pixel|kernel time|wall|host)' "$OUT/r.txt" | tr '\n' '|')"
  done
done
if [ "$(nvidia-smi -L | wc -l)" -gt 1 ]; then
  echo "== devices"
  $B/cohort devices
  for scene in confroom cornell; do
    for rep in 1 2; do
      for dev in 0 1 all; do
        $B/cohort render --scene $scene --width 1024 --height 1024 --paths "${PATHS:-512}" --devices $dev \
          --out "/tmp/$scene-$dev.exr" --png "/tmp/$scene-$dev.png" --stats "$OUT/$scene-$dev-$rep.json" > "$OUT/r.txt" 2>&1
        echo "$scene devices=$dev rep=$rep: $(grep -E '^(wall|paths/pixel|mean radiance)' "$OUT/r.txt" | tr '\n' '|')"
      done
    done
  done
fi
kill $smi
