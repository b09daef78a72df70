#!/usr/bin/env bash
# Writes the Markdown index of a results folder made by `make results`: for every experiment its
# printed tables, then its figures in the order of its report, each with the report's caption.
set -euo pipefail
dir=$1
shift
echo "# Figures of the reference experiments"
echo
echo "Made by \`make results\`: every experiment run with its default settings by the current"
echo "code. Tables as printed by \`physgrad run NAME\` (learning experiments: losses on the test"
echo "set); figures from its run folder with the captions of its report.html."
for name in "$@"; do
  echo
  echo "## $name"
  echo
  echo '```'
  grep -v '^report:' "$dir/$name.txt"
  echo '```'
  # The message (<p class="message"> on a line of its own), then <figure id="FILE"> …
  # <figcaption>CAPTION</figcaption>, one figure after another.
  awk -v name="$name" '
    /^<p class="message">.*<\/p>$/ { printf "\n%s\n", $0 }
    match($0, /<figure id="[^"]*">/) {
      file = substr($0, RSTART + 12, RLENGTH - 14)
    }
    match($0, /<figcaption>.*<\/figcaption>/) {
      caption = substr($0, RSTART + 12, RLENGTH - 25)
      printf "\n![%s](%s/%s)\n\n%s\n", file, name, file, caption
      file = ""
    }
    /<\/figure>/ && file != "" {
      printf "\n![%s](%s/%s)\n", file, name, file
      file = ""
    }
  ' "$dir/$name/report.html"
done
