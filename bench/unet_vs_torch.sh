#!/bin/sh
# ConvNetwork's 64×64 U-net against torch's network of the same shape, forward + backward at batch
# 128, on 1 and 2 threads, the two programs run alternately; prints a table of the best times
# (ms) and the ratios ours / torch.  Usage: bench/unet_vs_torch.sh [BUILD_DIR] [REPEATS]
set -eu
build=${1:-build}
repeats=${2:-3}
here=$(dirname "$0")
: "${OPENBLAS_CORETYPE:=$(grep -qw avx512bw /proc/cpuinfo && echo SkylakeX || echo Haswell)}"
export OPENBLAS_CORETYPE
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for threads in 1 2; do
  OMP_NUM_THREADS=$threads "$build/bench/physgrad_conv_bench" --threads=$threads \
    --benchmark_repetitions="$repeats" --benchmark_format=csv 2>/dev/null |
    awk -F, -v t="$threads" '/^"BM_UNetForwardBackward\/[01]\/iterations:1",/ {
      split($1, a, "/"); bn = substr(a[2], 1, 1); v = $3 + 0;
      key = "ours_bn" bn; if (!(key in best) || v < best[key]) best[key] = v }
      END { for (k in best) printf "%s %d %.1f\n", k, t, best[k] }' >> "$out"
  OMP_NUM_THREADS=$threads /usr/bin/python3 "$here/unet_torch.py" "$threads" "$repeats" |
    awk -v t="$threads" '{ printf "%s %d %s\n", $1, t, $2 }' >> "$out"
done
echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
printf '%-8s %-3s %10s %14s %14s %10s %10s\n' threads bn ours_ms torch_f64_ms torch_f32_ms 'ours/f64' 'ours/f32'
for threads in 1 2; do
  for bn in 0 1; do
    awk -v t="$threads" -v bn="$bn" '$2 == t { v[$1] = $3 }
      END { o = v["ours_bn" bn]; d = v["torch_f64_bn" bn]; f = v["torch_f32_bn" bn];
            printf "%-8d %-3d %10.0f %14.0f %14.0f %10.2f %10.2f\n", t, bn, o, d, f, o / d, o / f }' "$out"
  done
done
