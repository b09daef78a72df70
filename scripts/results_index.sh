#!/usr/bin/env bash
# Writes the Markdown index of a results folder made by `make results`: for every experiment
# its printed tables and its figures, in the order the experiments were run.
set -euo pipefail
dir=$1
shift
echo "# Figures of the reference experiments"
echo
echo "Made by \`make results\`: every experiment run with its default settings by the current"
echo "code. Tables as printed by \`physgrad run NAME\`; figures from its run folder."
for name in "$@"; do
  echo
  echo "## $name"
  echo
  echo '```'
  grep -v '^report:' "$dir/$name.txt"
  echo '```'
  for figure in "$dir/$name"/*.svg; do
    echo
    echo "![$(basename "$figure" .svg)]($name/$(basename "$figure"))"
  done
done
