#!/usr/bin/env bash
# Step time of data-parallel training with 1 and K ranks (default 2) on this machine: runs each
# configuration through the CLI alone and under mpiexec and prints the mean training seconds
# per step (evaluations excluded) from summary.json, with the ratio. Usage:
#   bench/distributed_steps.sh [BUILD_DIR] [K]
set -euo pipefail
build=${1:-build}
ranks=${2:-2}
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
  "sip, oscillators book, B 256|oscillators --variant book --optimizers sip --batch 256 --iters 100"
  "hig, hig-toy, B 128|hig-toy --optimizers hig --lambda 0.01 --seeds 1 --iters 2000"
)
seconds_per_step() {
  python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["runs"][0]; print(r["wall_seconds"]/r["iterations"])' "$1"
}
# "forward/derivatives/inversion/update" ms per step.
parts() {
  python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["runs"][0]; p=r["seconds_per_part"]; print("/".join("%.2f" % (1e3*p[k]/r["iterations"]) for k in ("forward","derivatives","inversion","update")))' "$1"
}
printf '%-34s %12s %12s %8s   %s\n' "configuration" "1 rank ms" "$ranks ranks ms" "ratio" \
  "parts ms, 1 rank | $ranks ranks (forward/derivatives/inversion/update)"
for entry in "${configs[@]}"; do
  label=${entry%%|*}
  args=${entry#*|}
  # Evaluations only at the start and the end (they are not part of the step time).
  common="--eval-every 1000000 --out"
  (cd "$work" && "$cli" run $args $common one > /dev/null 2>&1)
  (cd "$work" && mpiexec -n "$ranks" "$cli" run $args $common many > /dev/null 2>&1)
  one=$(seconds_per_step "$work/one/summary.json")
  many=$(seconds_per_step "$work/many/summary.json")
  python3 -c 'import sys; a,b=float(sys.argv[2]),float(sys.argv[3]); print("%-34s %12.3f %12.3f %8.2f   %s | %s" % (sys.argv[1], 1e3*a, 1e3*b, a/b, sys.argv[4], sys.argv[5]))' \
    "$label" "$one" "$many" "$(parts "$work/one/summary.json")" "$(parts "$work/many/summary.json")"
  rm -rf "$work/one" "$work/many"
done
