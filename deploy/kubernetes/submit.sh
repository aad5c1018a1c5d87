#!/usr/bin/env bash
# Runs a sharded render on a Kubernetes cluster: creates the shared volume (volume.yaml),
# the Indexed Job whose pod K renders shard K (render-job.yaml), waits for every index to
# complete, then runs the merge Job (merge-job.yaml) and waits for it. Edit the manifests
# first (image, SHARDS = completions, RUN, RENDER_ARGS, storage class, GPU requests).
#
#   deploy/kubernetes/submit.sh [kubectl options, e.g. -n NAMESPACE]
#
# $TIMEOUT bounds each wait (default 1h). The image is built from deploy/Dockerfile.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
timeout=${TIMEOUT:-1h}
kubectl "$@" apply -f "$here/volume.yaml"
kubectl "$@" apply -f "$here/render-job.yaml"
# A Job that fails never becomes complete: wait for either condition.
kubectl "$@" wait --for=condition=complete --timeout="$timeout" job/cohort-render &
complete=$!
kubectl "$@" wait --for=condition=failed --timeout="$timeout" job/cohort-render &
failed=$!
wait -n "$complete" "$failed" || true
if ! kubectl "$@" get job/cohort-render -o jsonpath='{.status.conditions[?(@.type=="Complete")].status}' | grep -q True; then
    kill "$complete" "$failed" 2>/dev/null || true
    echo "error: job cohort-render did not complete; see kubectl $* logs -l job-name=cohort-render" >&2
    exit 1
fi
kill "$failed" 2>/dev/null || true
kubectl "$@" apply -f "$here/merge-job.yaml"
kubectl "$@" wait --for=condition=complete --timeout="$timeout" job/cohort-merge
kubectl "$@" logs job/cohort-merge
