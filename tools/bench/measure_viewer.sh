#!/usr/bin/env bash
# Viewer size and open time for a long four-chain run (issue 17's figures):
# simulates robots/four_chains.yaml for STEPS steps (default 2000) with
# --export --planes, writes the viewer with `sdrs view`, and opens it in
# headless Chromium RUNS times (default 3). Prints the file size and, per
# run, the page's own time from navigation start to the first drawn frame
# (`data-ready-ms`: HTML parsed, three.js compiled, data decoded, meshes
# built, first render) and the wall time of the whole Chromium process
# (browser start-up to DOM dump). Release build; run with nice on a shared
# machine. Usage: bash tools/bench/measure_viewer.sh [STEPS] [RUNS]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
steps="${1:-2000}"
runs="${2:-3}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cd "$root"
cargo build --release -q -p sdrs-cli
sdrs="$root/target/release/sdrs"
t0=$(date +%s.%N)
"$sdrs" simulate robots/four_chains.yaml --steps "$steps" -q --export "$out/run" --planes
t1=$(date +%s.%N)
"$sdrs" view "$out/run" --out "$out/view.html"
t2=$(date +%s.%N)
"$sdrs" view "$out/run" --out "$out/view.glb"
echo "steps $steps: simulate+export+planes $(echo "$t1 - $t0" | bc) s, sdrs view $(echo "$t2 - $t1" | bc) s"
echo "contact records: $(($(wc -l <"$out/run/contacts.csv") - 1))"
echo "view.html: $(stat -c %s "$out/view.html") bytes; view.glb: $(stat -c %s "$out/view.glb") bytes"
for i in $(seq "$runs"); do
  s=$(date +%s.%N)
  dom=$(chromium --headless --no-sandbox --disable-gpu --use-angle=swiftshader --enable-unsafe-swiftshader \
    --no-first-run --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$out/profile$i" --dump-dom "file://$out/view.html#frame=0" 2>/dev/null)
  e=$(date +%s.%N)
  ready=$(grep -o 'data-ready-ms="[0-9]*"' <<<"$dom" | grep -o '[0-9]*')
  errors=$(grep -o 'data-errors="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' | head -1)
  echo "open $i: page ready ${ready} ms after navigation start; chromium process $(echo "$e - $s" | bc) s; errors ${errors}"
done
