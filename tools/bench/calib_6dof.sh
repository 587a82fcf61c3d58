#!/usr/bin/env bash
# Wall time of a 6-DOF calibration with every candidate (issue 33's benchmark line), two
# binaries interleaved. Robot: robots/calibrate/arm6.yaml (6 revolute joints under PD, Δt = 1 ms,
# 2 s). Data: the scene itself with a hidden `joint_damping` 0.3 on every joint, simulated by the
# AFTER binary (`sdrs simulate`), every 5th step kept (200 Hz), Gaussian noise σ = 1e-3 rad
# (numpy, seed 33). Each round runs `sdrs calibrate arm6.yaml --measured data.csv --out DIR -q`
# (each binary's default candidate set, i.e. every candidate it has) with BEFORE, then AFTER,
# at `nice -n 10`; `uptime` is recorded before and after every run. Prints one line per run and
# a table of the medians (wall, user, sys), with the verdict, chosen candidate, the number of
# ranked candidates and the simulations each binary reports.
#
#   tools/bench/calib_6dof.sh BEFORE_BIN AFTER_BIN [OUT_DIR] [ROUNDS]   (defaults out/bench_calib6, 3)
#
# Notes/calibration.md, session 8, has the figures of 2026-11-29 (before = 1759d5a, the commit
# before issue 33's first, 0f7d06b; after = 8883b59).
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -ge 2 ] || { echo "usage: $0 BEFORE_BIN AFTER_BIN [OUT_DIR] [ROUNDS]" >&2; exit 2; }
BEFORE=$1
AFTER=$2
OUT=${3:-out/bench_calib6}
ROUNDS=${4:-3}
for b in "$BEFORE" "$AFTER"; do
  [ -x "$b" ] || { echo "$0: $b is not an executable sdrs binary" >&2; exit 2; }
done
[[ "$ROUNDS" =~ ^[1-9][0-9]*$ ]] || { echo "$0: ROUNDS must be a positive integer, got '$ROUNDS'" >&2; exit 2; }
PY=${SDRS_PYTHON:-.venv/bin/python}
[ -x "$PY" ] || PY=python3
[ -x /usr/bin/time ] || { echo "$0: /usr/bin/time (GNU time) is needed" >&2; exit 2; }
mkdir -p "$OUT"

# Data (made once, by AFTER; both binaries read the same file).
{ cat robots/calibrate/arm6.yaml; printf 'effects:\n  - {effect: joint_damping, on: all, values: [0.3]}\n'; } > "$OUT/hidden.yaml"
nice -n 10 "$AFTER" simulate "$OUT/hidden.yaml" --out "$OUT/full.csv" -q > /dev/null
"$PY" - "$OUT" <<'PY'
import sys
import numpy as np
out = sys.argv[1]
rows = [l.strip().split(",") for l in open(f"{out}/full.csv") if l.strip()]
head, data = rows[0], np.array(rows[1:], dtype=float)
data = data[::5].copy()  # Δt = 1 ms → 200 Hz, t = 0 kept
rng = np.random.default_rng(33)
data[:, 1:] += 1e-3 * rng.standard_normal(data[:, 1:].shape)
with open(f"{out}/data.csv", "w") as f:
    f.write(",".join(head) + "\n")
    for r in data:
        f.write(",".join(repr(float(x)) for x in r) + "\n")
print(f"data: {len(data)} samples of {', '.join(head[1:])} → {out}/data.csv")
PY

LOG="$OUT/runs.tsv"
printf 'round\tbinary\twall_s\tuser_s\tsys_s\tload_before\tload_after\n' > "$LOG"
for r in $(seq 1 "$ROUNDS"); do
  for which in before after; do
    bin=$BEFORE; [ "$which" = after ] && bin=$AFTER
    dir="$OUT/${which}_$r"
    rm -rf "$dir"
    l0=$(cut -d' ' -f1-3 /proc/loadavg)
    /usr/bin/time -f '%e %U %S' -o "$OUT/time_${which}_$r" \
      nice -n 10 "$bin" calibrate robots/calibrate/arm6.yaml --measured "$OUT/data.csv" --out "$dir" -q > "$OUT/log_${which}_$r" 2>&1
    l1=$(cut -d' ' -f1-3 /proc/loadavg)
    read -r wall user sys < "$OUT/time_${which}_$r"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$r" "$which" "$wall" "$user" "$sys" "$l0" "$l1" | tee -a "$LOG"
  done
done

"$PY" - "$OUT" "$ROUNDS" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
lines = [l.rstrip("\n").split("\t") for l in open(f"{out}/runs.tsv")][1:]
print("| binary | wall s (median of %d) | runs | user s | sys s | verdict | candidate | candidates ranked | simulations |" % rounds)
print("|---|---:|---|---:|---:|---|---|---:|---:|")
med = {}
for which in ("before", "after"):
    rs = [l for l in lines if l[1] == which]
    wall = [float(l[2]) for l in rs]
    med[which] = statistics.median(wall)
    j = json.load(open(f"{out}/{which}_1/calibration.json"))
    print(f"| {which} | {med[which]:.2f} | {', '.join(f'{w:.2f}' for w in wall)} | "
          f"{statistics.median(float(l[3]) for l in rs):.2f} | {statistics.median(float(l[4]) for l in rs):.2f} | "
          f"{j['verdict']} | {j.get('candidate')} {json.dumps(j.get('parameters'))} | {len(j['ranking'])} | {j.get('simulations')} |")
print(f"after / before (median wall): {med['after'] / med['before']:.2f}")
PY
