#!/usr/bin/env bash
# Issue 19's full tunnelling grid (88 runs: shots at a 1 cm wall and a 2 mm
# plate at 20–100 m/s, a bar spinning at 10–100 rad/s against a post, a
# whipped chain, tumbling boxes dropped from 1–100 m onto a thin plate, a
# prismatic slider and a spherical arm; dt 0.005 and 0.01), each with and
# without continuous collision detection, plus python-fcl
# (tools/check/check_separation.py) on every exported CCD run.
#
#   tools/bench/tunnel_grid.sh [OUT_DIR]      (default out/tunnel_grid)
#
# Prints the markdown table of `examples/tunnel_grid.rs` and one line per
# fcl check; exits 1 if any CCD run crosses an obstacle or fcl finds an
# interpenetrating state. Takes about a minute in release.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-out/tunnel_grid}
rm -rf "$OUT"
mkdir -p "$OUT"
cargo run --release -q --example tunnel_grid -- --fcl "$OUT"
bad=0
n=0
for d in "$OUT"/*/; do
  n=$((n + 1))
  if ! .venv/bin/python tools/check/check_separation.py "$d" > "$d/fcl.json"; then
    echo "python-fcl: violation in $d"
    bad=$((bad + 1))
  fi
done
echo "python-fcl: $n exported CCD runs checked, $bad with interpenetration"
[ "$bad" -eq 0 ]
