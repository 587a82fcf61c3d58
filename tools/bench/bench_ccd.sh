#!/usr/bin/env bash
# Cost of continuous collision detection on the four-chain benchmark
# (issue 19): `sdrs bench` (release) with CCD on (the default) and off
# (`contact.ccd.enabled: false`), interleaved REPS times, N = 2…32 links per
# chain, 200 steps each. Prints, per N, the median ms/step on and off, the
# slowdown, Newton iterations and the `ccd` stage's share of the step time.
#
#   [STEPS=200] tools/bench/bench_ccd.sh [OUT_DIR] [REPS]     (defaults out/bench_ccd, 3)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-out/bench_ccd}
REPS=${2:-3}
STEPS=${STEPS:-200}
BIN=${SDRS_BIN:-target/release/sdrs}
[ -n "${SDRS_BIN:-}" ] || cargo build --release -q
mkdir -p "$OUT"
cp robots/four_chains.yaml "$OUT/on.yaml"
sed 's/^contact: {\(.*\)}$/contact: {\1, ccd: {enabled: false}}/' robots/four_chains.yaml > "$OUT/off.yaml"
grep -q "enabled: false" "$OUT/off.yaml" || { echo "could not switch CCD off in $OUT/off.yaml"; exit 2; }
for i in $(seq 1 "$REPS"); do
  for s in on off; do
    nice -n 5 "$BIN" bench --scene "$OUT/$s.yaml" --steps "$STEPS" --json "$OUT/${s}_$i.json" > /dev/null
  done
done
.venv/bin/python - "$OUT" "$REPS" <<'PY'
import json, statistics, sys
out, reps = sys.argv[1], int(sys.argv[2])
runs = {s: [json.load(open(f"{out}/{s}_{i}.json")) for i in range(1, reps + 1)] for s in ("on", "off")}
print("| links/chain | dof | ms/step on | ms/step off | slowdown | Newton it/step on / off | ccd share of the step (on) |")
print("|---:|---:|---:|---:|---:|---|---:|")
for k, row in enumerate(runs["on"][0]):
    on = [r[k] for r in runs["on"]]
    off = [r[k] for r in runs["off"]]
    m_on = statistics.median(x["ms_per_step"] for x in on)
    m_off = statistics.median(x["ms_per_step"] for x in off)
    share = statistics.median(
        sum(s["seconds"] for s in x["stages"] if s["stage"] == "ccd") / sum(s["seconds"] for s in x["stages"])
        for x in on)
    print(f"| {row['links_per_chain']} | {row['dof']} | {m_on:.3f} | {m_off:.3f} | {100 * (m_on / m_off - 1):+.1f}% | "
          f"{on[0]['newton_iterations_per_step']:.2f} / {off[0]['newton_iterations_per_step']:.2f} | {100 * share:.1f}% |")
PY
