#!/usr/bin/env bash
# Where the four chains' time goes, step by step, in SDRS and MuJoCo: each
# step's minimum wall time over ROUNDS runs of the same trajectory (the
# minimum removes the machine's interruptions), split into steps with and
# without contact (SDRS: an active pair; MuJoCo: ncon > 0). SDRS runs
# `examples/step_classes.rs` on THREADS threads (default 1, like MuJoCo's
# mj_step); MuJoCo runs `step_classes.py mujoco` (bench_mujoco.py's chains).
# For each N the two engines run one after the other. Prints the load
# before and after and one table row per N.
#
#   tools/bench/step_classes.sh [--links 4,8,16] [--steps 600] [--rounds 7] [--threads 1] [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
links="4,8,16"; steps=600; rounds=7; threads=1; out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --links) links="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
for v in "$steps" "$rounds" "$threads"; do
  [[ "$v" =~ ^[1-9][0-9]*$ ]] || { echo "--steps, --rounds and --threads take positive integers, got '$v'" >&2; exit 2; }
done
py="${PYTHON:-.venv/bin/python}"
[ -x "$py" ] || py=python3
cargo build --release -q --example step_classes
work="${out:-$(mktemp -d)}"
mkdir -p "$work"
echo "load before: $(uptime)"
for n in ${links//,/ }; do
  "$py" tools/bench/step_classes.py chains --links "$n" --out "$work/chains$n.yaml"
  RAYON_NUM_THREADS="$threads" target/release/examples/step_classes "$work/chains$n.yaml" "$steps" "$rounds" > "$work/sdrs$n.csv"
  "$py" tools/bench/step_classes.py mujoco --links "$n" --steps "$steps" --rounds "$rounds" --out "$work/mj$n.csv"
done
echo "load after:  $(uptime)"
echo "steps: $steps, rounds (minimum per step): $rounds, sdrs threads: $threads (MuJoCo: one), files: $work"
"$py" tools/bench/step_classes.py summarize "$work" ${links//,/ }
