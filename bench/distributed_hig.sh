#!/usr/bin/env bash
# The HIG step on Poisson (8×8 grid, m = 64 outputs per sample) at J J^T sizes n = 64·B, on one
# rank and on K ranks (default 2), with the Gram eigendecomposition repeated on every rank
# (--distributed-gram-rows 0) and shared among the ranks (ScaLAPACK, --distributed-gram-rows 1),
# all in one run: R rounds (default 3), the configurations alternating within each round. Prints
# per configuration the median training seconds per step (evaluations excluded, summary.json),
# its parts (derivatives = physics VJPs + forming J J^T; inversion = eigendecomposition + J^T c),
# the largest resident set of any rank (/usr/bin/time -v) and, for the runs on K ranks, the bytes
# the busiest rank handed to MPI per step (bench/mpi_traffic.c, when the build has it; the run's
# set-up and evaluations, a few kB, are included), with the load average at the start.
# Usage: bench/distributed_hig.sh [BUILD_DIR] [K] [R] [SIZES] [CONFIGS]
#   SIZES default "1024 2048 4096"; CONFIGS a subset of "0 1 2" (one rank, every rank solves,
#   shared), all three by default.
set -euo pipefail
build=${1:-build}
ranks=${2:-2}
repeats=${3:-3}
sizes=${4:-"1024 2048 4096"}
configs=${5:-"0 1 2"}
cli=$(cd "$build" && pwd)/physgrad
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OPENBLAS_NUM_THREADS=1
# Ranks waiting in a collective yield the core (this machine is often oversubscribed).
export OMPI_MCA_mpi_yield_when_idle=1

echo "load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)"
# "seconds_per_step derivatives inversion" of a run folder.
step_figures() {
  python3 -c 'import json,sys
r = json.load(open(sys.argv[1]))["runs"][0]; n = r["iterations"]; p = r["seconds_per_part"]
print("%.4f %.4f %.4f" % (r["wall_seconds"] / n, p["derivatives"] / n, p["inversion"] / n))' "$1"
}
# Largest "Maximum resident set size" (kB) in a /usr/bin/time -v log (one per rank).
max_rss() { awk '/Maximum resident set size/ {if ($6 > m) m = $6} END {print m}' "$1"; }
# Most bytes any rank sent ("mpi_traffic: rank R of K sent B bytes …" lines; 0 without them).
max_sent() { awk '/^mpi_traffic:/ {if ($7 > m) m = $7} END {print m + 0}' "$1"; }
traffic=$(cd "$build" && pwd)/bench/libphysgrad_mpi_traffic.so
preload=()
[ -f "$traffic" ] && preload=(env "LD_PRELOAD=$traffic")

printf '%-6s %-28s %10s %10s %10s %12s %14s\n' n configuration "s/step" "deriv s" "invert s" \
  "max RSS MB" "sent MB/step"
for n in $sizes; do
  batch=$((n / 64))
  steps=$(( n >= 4096 ? 1 : 2 ))
  args="poisson --optimizers hig --batch $batch --train-size $((batch * 4)) --test-size 64 \
--iters $steps --time 100000 --eval-every 1000000"
  labels=("1 rank" "$ranks ranks, every rank solves" "$ranks ranks, shared solve")
  launch=("" "mpiexec -n $ranks" "mpiexec -n $ranks")
  rows=(0 0 1)
  declare -A results=()
  for round in $(seq "$repeats"); do
    for c in $configs; do
      out="$work/c$c-$round"
      wrap=()
      [ "$c" != 0 ] && wrap=("${preload[@]}")
      (cd "$work" && ${launch[$c]} /usr/bin/time -v "${wrap[@]}" "$cli" run $args \
         --distributed-gram-rows "${rows[$c]}" --out "$out" > /dev/null 2> "$out.time")
      results[$c]+="$(step_figures "$out/summary.json") $(max_rss "$out.time") \
$(( $(max_sent "$out.time") / steps ))
"
      rm -rf "$out"
    done
  done
  for c in $configs; do
    python3 -c 'import sys, statistics as st
rows = [list(map(float, l.split())) for l in sys.argv[3].strip().splitlines()]
med = [st.median(col) for col in zip(*rows)]
print("%-6s %-28s %10.3f %10.3f %10.3f %12.0f %14.1f   (all s/step: %s)" % (sys.argv[1],
      sys.argv[2], med[0], med[1], med[2], med[3] / 1024, med[4] / 1e6,
      " ".join("%.3f" % r[0] for r in rows)))' \
      "$n" "${labels[$c]}" "${results[$c]}"
  done
done
