#!/usr/bin/env bash
# The paper's locomotion benchmarks (issue 11): spider on a 15° slope and
# biped, co-design vs controller-only (--design off), from the same start.
#
#   tools/bench/bench_locomotion.sh [OUT_DIR] [SPIDER_ITERS] [BIPED_ITERS]
#
# Defaults: out/bench_locomotion, 300 and 300 iterations (the paper does not
# give its iteration counts; see notes/locomotion.md for what was run). Runs two
# streams in parallel under `nice -n 5` (co-design / controller-only), each
# spider then biped, with a checkpoint every iteration: an interrupted run
# continues with `sdrs optimize robots/<r>/task.yaml --resume DIR [--design
# off] --iters N`. Prints a markdown table from the summary.json files.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-out/bench_locomotion}
SI=${2:-300}
BI=${3:-300}
# SDRS_WRAP: a command prefix for each run (e.g. a machine-wide job
# semaphore); default none.
WRAP=${SDRS_WRAP:-}
# SDRS_BIN: a fixed copy of the binary (so that rebuilding during a long run
# does not change the second half of a stream).
BIN=${SDRS_BIN:-target/release/sdrs}
[ -n "${SDRS_BIN:-}" ] || cargo build --release -q
mkdir -p "$OUT"
run() { # robot design iters
  local dir="$OUT/$1_$2"
  if [ -f "$dir/checkpoint.json" ] && [ ! -f "$dir/summary.json" ]; then
    $WRAP nice -n 5 "$BIN" optimize "robots/$1/task.yaml" --design "$2" --iters "$3" --resume "$dir" -q
  else
    $WRAP nice -n 5 "$BIN" optimize "robots/$1/task.yaml" --design "$2" --iters "$3" --out "$dir" --force -q
  fi
}
( run spider on "$SI"; run biped on "$BI" ) > "$OUT/stream_on.log" 2>&1 &
A=$!
( run spider off "$SI"; run biped off "$BI" ) > "$OUT/stream_off.log" 2>&1 &
B=$!
wait $A $B
python3 tools/gen/locomotion_table.py "$OUT"
