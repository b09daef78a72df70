#!/usr/bin/env bash
# Step time of data-parallel training with 1 and K ranks (default 2) on this machine: runs each
# configuration through the CLI alone and under mpiexec, alternately, R times (default 3), and
# prints the smallest mean training seconds per step (evaluations excluded, from summary.json)
# of each, their ratio, and the time per part of those runs. Usage:
#   bench/distributed_steps.sh [BUILD_DIR] [K] [R]
set -euo pipefail
build=${1:-build}
ranks=${2:-2}
repeats=${3:-3}
cli=$(cd "$build" && pwd)/physgrad
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root (containers) and more ranks than cores unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OPENBLAS_NUM_THREADS=1

configs=(
  "hig, oscillators paper, B 128|oscillators --optimizers hig --batch 128 --iters 60"
  "gn, oscillators paper, B 128|oscillators --optimizers gn --batch 128 --iters 60"
  "adam, oscillators paper, B 512|oscillators --optimizers adam --batch 512 --iters 200"
  "sip, oscillators book, B 256|oscillators --variant book --optimizers sip --batch 256 --iters 60"
  "hig, hig-toy, B 128|hig-toy --optimizers hig --lambda 0.01 --seeds 1 --iters 2000"
)
# "ms_per_step forward/derivatives/inversion/update" of a run folder.
step_figures() {
  python3 -c 'import json,sys
r = json.load(open(sys.argv[1]))["runs"][0]; n = r["iterations"]; p = r["seconds_per_part"]
print("%.3f" % (1e3 * r["wall_seconds"] / n),
      "/".join("%.2f" % (1e3 * p[k] / n) for k in ("forward", "derivatives", "inversion", "update")))' "$1"
}
printf '%-32s %10s %10s %7s   %s\n' "configuration" "1 rank ms" "$ranks ranks ms" "ratio" \
  "ms per part, 1 rank | $ranks ranks (forward/derivatives/inversion/update)"
for entry in "${configs[@]}"; do
  label=${entry%%|*}
  args=${entry#*|}
  best_one="" best_many=""
  for _ in $(seq "$repeats"); do
    # Evaluations only at the start and the end (they are not part of the step time).
    (cd "$work" && "$cli" run $args --eval-every 1000000 --out one > /dev/null 2>&1)
    (cd "$work" && mpiexec -n "$ranks" "$cli" run $args --eval-every 1000000 --out many \
       > /dev/null 2>&1)
    one=$(step_figures "$work/one/summary.json")
    many=$(step_figures "$work/many/summary.json")
    if [ -z "$best_one" ] || python3 -c 'import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) else 1)' "${one%% *}" "${best_one%% *}"; then best_one=$one; fi
    if [ -z "$best_many" ] || python3 -c 'import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) else 1)' "${many%% *}" "${best_many%% *}"; then best_many=$many; fi
    rm -rf "$work/one" "$work/many"
  done
  python3 -c 'import sys
a, b = float(sys.argv[2].split()[0]), float(sys.argv[3].split()[0])
print("%-32s %10.3f %10.3f %7.2f   %s | %s" % (sys.argv[1], a, b, a / b, sys.argv[2].split()[1], sys.argv[3].split()[1]))' \
    "$label" "$best_one" "$best_many"
done
