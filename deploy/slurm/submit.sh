#!/usr/bin/env bash
# Renders one image as N shards on a Slurm cluster and merges them:
#
#   deploy/slurm/submit.sh N OUT_DIR [cohort render options...]
#   e.g. deploy/slurm/submit.sh 16 /shared/run1 --scene cornell --width 1024 --height 1024 --paths 4096
#
# submits a job array of N tasks (render-array.sbatch: task K renders --shard K/N) and a
# merge job that starts only when every task has succeeded (merge.sbatch), and prints
# both job ids. OUT_DIR must be on a file system every node sees. Extra sbatch options
# go in $SBATCH_OPTIONS (both jobs: partition, account, time limit) and
# $RENDER_SBATCH_OPTIONS (the render tasks only: GPUs, e.g. "--gres=gpu:1"). $COHORT (the
# binary) is passed on to the jobs.
set -euo pipefail

n=${1:?usage: submit.sh N OUT_DIR [cohort render options...]}
out_dir=${2:?usage: submit.sh N OUT_DIR [cohort render options...]}
shift 2
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out_dir"
out_dir=$(cd "$out_dir" && pwd)
# shellcheck disable=SC2086 # SBATCH_OPTIONS is a list of options.
array=$(sbatch --parsable ${SBATCH_OPTIONS:-} ${RENDER_SBATCH_OPTIONS:-} --array="0-$((n - 1))" --output="$out_dir/slurm-%A_%a.out" \
    "$here/render-array.sbatch" "$out_dir" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_OPTIONS:-} --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --output="$out_dir/slurm-merge-%j.out" "$here/merge.sbatch" "$out_dir" "$n")
merge=${merge%%;*}
echo "array job $array ($n shards), merge job $merge: $out_dir/final.exr"
