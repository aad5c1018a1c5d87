#!/usr/bin/env bash
# The Kubernetes recipe (deploy/kubernetes) without a cluster: reads the manifests,
# checks what the recipe depends on (an Indexed Job whose SHARDS equals its completions,
# the same SHARDS, RUN and volume in the merge Job), then runs each container's own
# command here as the Job controller would run it — render-job.yaml once per completion
# index with JOB_COMPLETION_INDEX set, then merge-job.yaml — with DATA pointing at a
# temporary directory instead of the shared volume, and compares the merged image with
# an unsplit render (`cohort compare`). What it cannot test is Kubernetes itself
# (scheduling, the volume, the image from deploy/Dockerfile). Needs python3 with PyYAML
# (Debian's python3-yaml, installed when missing); RENDER_ARGS is replaced by a small
# render unless given. $COHORT is the binary to test (default: a debug build, made here).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
fail() {
    echo "kubernetes local test: FAILED: $*" >&2
    exit 1
}
if ! python3 -c 'import yaml' 2>/dev/null; then
    sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq python3-yaml >/dev/null ||
        fail "needs python3 with PyYAML (python3-yaml)"
fi
if [ -z "${COHORT:-}" ]; then
    cargo build --locked -p cohort-cli
    COHORT=$repo/target/debug/cohort
fi
work=$(mktemp -d /tmp/cohort-k8s.XXXXXX)
trap 'rm -rf "$work"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$work/xdg}
mkdir -p "$XDG_RUNTIME_DIR" "$work/bin" "$work/data" && chmod 700 "$XDG_RUNTIME_DIR"
# The containers call `cohort` on PATH.
ln -s "$COHORT" "$work/bin/cohort"
render_args=${RENDER_ARGS:---scene cornell --width 32 --height 32 --paths 12 --integrator nee}

# Prints, one per line: the completion count, then NAME=VALUE of the render container's
# env, a line `--`, the merge container's env, and writes each container's shell script
# to $work/render.sh and $work/merge.sh. Fails naming what breaks the recipe.
python3 - "$work" >"$work/manifest.txt" <<'PY' || fail "the manifests do not hold together (above)"
import sys, yaml
work = sys.argv[1]
def load(name):
    docs = [d for d in yaml.safe_load_all(open(f"deploy/kubernetes/{name}")) if d]
    assert len(docs) == 1, f"{name}: expected one object, found {len(docs)}"
    return docs[0]
def container(job, name):
    pod = job["spec"]["template"]["spec"]
    assert pod["restartPolicy"] == "Never", f"{name}: restartPolicy should be Never"
    (c,) = pod["containers"]
    cmd = c["command"]
    assert cmd[:2] == ["/bin/sh", "-c"] and len(cmd) == 3, f"{name}: command is not /bin/sh -c SCRIPT"
    env = {e["name"]: e["value"] for e in c["env"]}
    mounts = {m["name"]: m["mountPath"] for m in c["volumeMounts"]}
    claims = {v["name"]: v["persistentVolumeClaim"]["claimName"] for v in pod["volumes"]}
    assert list(mounts.values()) == [env["DATA"]], f"{name}: the volume is not mounted at DATA={env['DATA']}"
    return c, env, cmd[2], claims
pvc = load("volume.yaml")
assert pvc["kind"] == "PersistentVolumeClaim" and "ReadWriteMany" in pvc["spec"]["accessModes"], "volume.yaml: not a ReadWriteMany claim"
render, merge = load("render-job.yaml"), load("merge-job.yaml")
assert render["spec"]["completionMode"] == "Indexed", "render-job.yaml: not an Indexed Job"
n = render["spec"]["completions"]
_, renv, rscript, rclaims = container(render, "render-job.yaml")
_, menv, mscript, mclaims = container(merge, "merge-job.yaml")
assert renv["SHARDS"] == str(n), f"render-job.yaml: SHARDS={renv['SHARDS']} but completions={n}"
for key in ["SHARDS", "RUN", "DATA"]:
    assert renv[key] == menv[key], f"{key} differs: {renv[key]} (render) vs {menv[key]} (merge)"
assert set(rclaims.values()) == set(mclaims.values()) == {pvc["metadata"]["name"]}, "the Jobs do not mount the volume of volume.yaml"
assert "JOB_COMPLETION_INDEX" in rscript, "render-job.yaml: the command does not use JOB_COMPLETION_INDEX"
open(f"{work}/render.sh", "w").write(rscript)
open(f"{work}/merge.sh", "w").write(mscript)
print(n)
for k, v in renv.items():
    print(f"{k}={v}")
print("--")
for k, v in menv.items():
    print(f"{k}={v}")
PY
n=$(head -1 "$work/manifest.txt")
mapfile -t render_env < <(sed -n '2,/^--$/p' "$work/manifest.txt" | grep -v '^--$')
mapfile -t merge_env < <(sed -n '/^--$/,$p' "$work/manifest.txt" | tail -n +2)
run=$(printf '%s\n' "${render_env[@]}" | sed -n 's/^RUN=//p')
echo "kubernetes local test: $n completion indices, then the merge (RENDER_ARGS: $render_args)"
for ((k = 0; k < n; k++)); do
    env "${render_env[@]}" DATA="$work/data" RENDER_ARGS="$render_args" JOB_COMPLETION_INDEX=$k \
        PATH="$work/bin:$PATH" /bin/sh -c "$(cat "$work/render.sh")" >"$work/render-$k.log" 2>&1 ||
        { cat "$work/render-$k.log" >&2; fail "index $k failed"; }
    grep -q "shard          $k/$n" "$work/render-$k.log" || fail "index $k did not render shard $k/$n"
done
# An index past SHARDS (completions changed, SHARDS not) fails clearly.
if env "${render_env[@]}" DATA="$work/data" RENDER_ARGS="$render_args" JOB_COMPLETION_INDEX=$n \
    PATH="$work/bin:$PATH" /bin/sh -c "$(cat "$work/render.sh")" 2>"$work/extra.log"; then
    fail "index $n of $n shards did not fail"
fi
grep -q "set SHARDS to the Job's completions" "$work/extra.log" || fail "index $n failed without saying why"
env "${merge_env[@]}" DATA="$work/data" PATH="$work/bin:$PATH" /bin/sh -c "$(cat "$work/merge.sh")" ||
    fail "the merge Job's command failed"
# shellcheck disable=SC2086 # a list of options, as the manifest splits it.
"$COHORT" render $render_args --out "$work/whole.exr" --png "$work/whole.png" >/dev/null
"$COHORT" compare "$work/data/$run/final.exr" "$work/whole.exr" || fail "the merged shards differ from the unsplit render"
echo "kubernetes local test: passed ($n indices of the Indexed Job, merged, match the unsplit render)"
