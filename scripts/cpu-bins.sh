# Sourced by the scripts that compare CPU-backend builds on a machine's cores
# (cpu-many-cores.sh, cpu-exit-under-compile.sh): enters the folder of builds ($B, default
# the current one), unpacks any xz-compressed build, sets $BINS (default "cohort-old
# cohort") and a private XDG_RUNTIME_DIR, and prints the machine and the time.
cd "${B:-.}" || exit 1
BINS="${BINS:-cohort-old cohort}"
for f in *.xz; do [ -e "$f" ] && xz -d -k -f "$f" && chmod +x "${f%.xz}"; done
export XDG_RUNTIME_DIR=$(mktemp -d); chmod 700 "$XDG_RUNTIME_DIR"
echo "$(nproc) cores; $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%FT%TZ)"
