#!/usr/bin/env bash
# The paper's grasping benchmarks (issue 12), full runs: each task with
# co-design and its `--design off` twin, wall times, and the independent
# python-fcl interpenetration check of every optimized trajectory.
#
#   bash tools/bench/bench_grasping.sh [OUT=out/grasping] [TASKS="parallel_jaw_gripper single_jaw_gripper single_jaw_cross three_finger_hand"]
#
# Iterations: the task's `optimizer.iters` unless ITERS is set. Runs under
# `nice -n 5` (the machine is shared). Prints a table; the per-run outputs
# (summary.json with the grasp and topology metrics, history.csv, meshes/,
# scenes/, design.yaml) are in $OUT/<task>/{on,off}/.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${OUT:-out/grasping}
TASKS=${TASKS:-"parallel_jaw_gripper single_jaw_gripper single_jaw_cross three_finger_hand"}
PY=${PY:-.venv/bin/python}
[ -n "${SKIP_BUILD:-}${SDRS_BIN:-}" ] || cargo build --release -q  # SKIP_BUILD=1: use the built binary
BIN=${SDRS_BIN:-target/release/sdrs}  # SDRS_BIN: a fixed copy of the binary
mkdir -p "$OUT"
for t in $TASKS; do
  task=robots/$t/task.yaml
  [ -f "$task" ] || { echo "$t: no task.yaml, skipped"; continue; }
  for mode in on off; do
    dir=$OUT/$t/$mode
    rm -rf "$dir"
    start=$SECONDS
    nice -n 5 "$BIN" optimize "$task" --out "$dir" --design $mode -q ${ITERS:+--iters $ITERS}

    echo $((SECONDS - start)) > "$dir/wall_seconds.txt"
    # Independent check: replay each optimized scene and ask python-fcl.
    : > "$dir/separation.txt"
    for s in "$dir"/scenes/*.yaml; do
      h=$($PY -c "import json;print(json.load(open('$dir/summary.json'))['horizon'])")
      ex=$dir/export/$(basename "$s" .yaml)
      nice -n 5 "$BIN" simulate "$s" --steps "$h" --export "$ex" -q --out "$ex.csv"
      if $PY tools/check/check_separation.py "$ex" > "$ex.separation.json"; then
        echo "$(basename "$s"): separated" >> "$dir/separation.txt"
      else
        echo "$(basename "$s"): INTERPENETRATION (see $ex.separation.json)" >> "$dir/separation.txt"
      fi
    done
  done
done
$PY - "$OUT" $TASKS <<'PY'
import json, sys
from pathlib import Path
out = Path(sys.argv[1])
print("| task | design | iterations | loss initial → final (best) | grasped before → after | topology (b0,b1,b2) before → after | lifted (all) | wall (s) | fcl check |")
print("|---|---|---|---|---|---|---|---|---|")
for t in sys.argv[2:]:
    for mode in ("on", "off"):
        d = out / t / mode
        if not (d / "summary.json").exists():
            continue
        s = json.loads((d / "summary.json").read_text())
        m = s["extra"]["metrics"]
        g = m["grasp"]
        lifted = all(x["lifted"] for x in g["after"]) if g["after"] else None
        sep = (d / "separation.txt").read_text()
        ok = "ok" if "INTERPENETRATION" not in sep and sep.strip() else "FAIL"
        betti = lambda x: f"({x['components']},{x['holes']},{x['cavities']})"
        topo = "; ".join(f"{k}: {betti(v)} → {betti(m['topology']['after'][k])}"
                         for k, v in m["topology"]["before"].items()) or "—"
        best = s["initial_loss"]
        hist = d / "history.csv"
        if hist.exists():
            rows = hist.read_text().splitlines()[1:]
            best = min([float(r.split(",")[2]) for r in rows] + [best])
        print(f"| {t} | {mode} | {s['iterations']} | {s['initial_loss']:.3e} → {s['final_loss']:.3e} ({best:.3e}) | "
              f"{g['grasped_before']}/{g['trajectories']} → {g['grasped_after']}/{g['trajectories']} | "
              f"{topo} | {lifted} | {float((d / 'wall_seconds.txt').read_text()):.0f} | {ok} |")
PY
