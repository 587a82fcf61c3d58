#!/usr/bin/env bash
# SDRS vs MuJoCo on the four rotating chains (robots/four_chains.yaml), the
# two engines interleaved in one run: for each round, for each N, first
# `sdrs bench --links N`, then `tools/bench/bench_mujoco.py --links N` (the same
# chains: masses, inertias, PD gains, dt, friction; MuJoCo's `implicit`
# integrator). Prints per N the ms/step of both, their ratio (median over
# rounds), Newton iterations per step, the SDRS stage shares (medians over
# rounds; the linear solve's range over rounds at the largest N), and the
# growth exponents over N = 8…32. The machine's load is printed before and
# after. SDRS runs on `--threads` threads (default 1, `RAYON_NUM_THREADS`):
# MuJoCo's `mj_step` on one model uses one thread, so one against one is the
# like-for-like comparison; `--threads 2` shows what the pair work and the
# block solves gain from a second core. `--repeats K` (default 1) times each
# engine's trajectory K times within a round and keeps the fastest of each:
# a round is then robust to the machine's interruptions (one 600-step run at
# N = 8 lasts about 60 ms, and single runs spread by ±25 % on a shared VM).
#
#   tools/bench/bench_vs_mujoco.sh [--links 2,4,8,16,32] [--steps 600] [--rounds 1]
#                            [--repeats 1] [--threads 1] [--sdrs target/release/sdrs]
#                            [--out rows.jsonl]
#                            [-- extra sdrs bench arguments, e.g. --contact sdrs]
#
# Build first: cargo build --release -p sdrs-cli (or `cargo build --release`).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$(dirname "$here")")"
links="2,4,8,16,32"
steps=600
rounds=1
repeats=1
threads=1
sdrs="$root/target/release/sdrs"
out=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --links) links="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --repeats) repeats="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --sdrs) sdrs="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
py="${PYTHON:-$root/.venv/bin/python}"
[ -x "$py" ] || py=python3
[[ "$threads" =~ ^[1-9][0-9]*$ ]] || { echo "--threads must be a positive integer, got '$threads'" >&2; exit 2; }
[[ "$repeats" =~ ^[1-9][0-9]*$ ]] || { echo "--repeats must be a positive integer, got '$repeats'" >&2; exit 2; }
[ -x "$sdrs" ] || { echo "no sdrs binary at $sdrs (cargo build --release)" >&2; exit 2; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
rows="${out:-$work/rows.jsonl}"
: > "$rows"
echo "load before: $(uptime)"
for r in $(seq 1 "$rounds"); do
  for n in ${links//,/ }; do
    RAYON_NUM_THREADS="$threads" "$sdrs" bench --links "$n" --steps "$steps" --repeats "$repeats" --json "$work/s.json" "${extra[@]}" > "$work/s.txt"
    "$py" - "$work/s.json" "$rows" <<'EOF'
import json, sys
rows = json.load(open(sys.argv[1]))
with open(sys.argv[2], "a") as f:
    for r in rows:
        r["engine"] = "sdrs"
        f.write(json.dumps(r) + "\n")
EOF
    "$py" "$here/bench_mujoco.py" --links "$n" --steps "$steps" --repeats "$repeats" --json "$work/m.json" > /dev/null
    cat "$work/m.json" >> "$rows"
  done
done
echo "load after:  $(uptime)"
echo "steps per run: $steps, rounds: $rounds, fastest of $repeats run(s) per engine and round, sdrs threads: $threads (MuJoCo: one)"
echo "sdrs: $sdrs ($("$sdrs" --version 2>/dev/null || echo unknown version))"
"$py" "$here/bench_mujoco.py" summarize "$rows"
