#!/usr/bin/env bash
# The single jaw's second task (robots/single_jaw_cross, issue 30): the runs
# and the isolating experiment of notes/grasping-topology-change.md part 2 §8.
#
#   bash tools/bench/single_jaw_cross.sh [OUT=out/single_jaw_cross]
#
# 1. co-design, `--design off`, and the design alone (no controller
#    variables) with the trust region, and the design alone with Adam
#    (lr 2e-3); each prints loss, grasp and the jaw's topology;
# 2. the loss, grasp and `holes` along the straight line in design space
#    from the initial jaw to a 12 mm square hole (fraction 0 … 1 of
#    tools/gen/make_grasp_scenes.py `drill`), and finely between 0.3 and 0.5.
# 3. a picture of the right leg seen along the arm ($OUT/single_jaw_cross.png).
# About 10 minutes on 2 cores. Runs under `nice -n 5`; SKIP_BUILD=1 uses the
# built binary.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${OUT:-out/single_jaw_cross}
PY=${PY:-.venv/bin/python}
[ -n "${SKIP_BUILD:-}${SDRS_BIN:-}" ] || cargo build --release -q
BIN=${SDRS_BIN:-$PWD/target/release/sdrs}  # SDRS_BIN: a fixed copy of the binary
TASK=robots/single_jaw_cross/task.yaml
mkdir -p "$OUT"
cp robots/single_jaw_cross/scene.yaml "$OUT/scene.yaml"
sed 's/^  joints: \[gripper\/base\]/  joints: []/' "$TASK" > "$OUT/task_design_alone.yaml"
sed -e 's/method: trust_region/method: adam/' -e '/radius: /d' "$OUT/task_design_alone.yaml" > "$OUT/task_design_alone_adam.yaml"
run() {  # name task [args]
  local name=$1 task=$2; shift 2
  nice -n 5 "$BIN" optimize "$task" --out "$OUT/$name" --force -q "$@" || echo "$name: run failed"
}
run codesign "$TASK"
run controller_only "$TASK" --design off
run design_alone "$OUT/task_design_alone.yaml"
run design_alone_adam "$OUT/task_design_alone_adam.yaml"
"$PY" - "$OUT" "$BIN" <<'PY'
import json, subprocess, sys
from pathlib import Path
import yaml
out, bin_ = Path(sys.argv[1]), sys.argv[2]
sys.path.insert(0, "tools/gen")
from make_grasp_scenes import drill  # the hand-made hole
def row(d):
    s = json.loads((d / "summary.json").read_text())
    m = s["extra"]["metrics"]; g = m["grasp"]["after"][0]
    t = (m["topology"]["after"] or m["topology"]["before"])["gripper/jaw"]
    return s["initial_loss"], s["final_loss"], g, t["holes"]
print("| run | loss initial → result | lifted | drift (m) | rise (m) | jaw holes |")
print("|---|---|---|---|---|---|")
for name in ["codesign", "controller_only", "design_alone", "design_alone_adam"]:
    d = out / name
    if (d / "summary.json").exists():
        l0, l1, g, h = row(d)
        print(f"| {name} | {l0:.4e} → {l1:.4e} | {g['lifted']} | {g['max_drift']:.3f} | {g['rise']:.4f} | {h} |")
base = yaml.safe_load((out / "scene.yaml").read_text())
task = (out / "task_design_alone.yaml").read_text()
print("\n| fraction of the 12 mm hole | loss | grasped | drift (m) | rise (m) | jaw holes |")
print("|---|---|---|---|---|---|")
for f in [0.0, 0.1, 0.2, 0.3, 0.34, 0.36, 0.38, 0.4, 0.44, 0.48, 0.5, 0.6, 0.8, 1.0]:
    d = out / f"line_{f:.2f}"; d.mkdir(exist_ok=True)
    s = yaml.safe_load((out / "scene.yaml").read_text())
    drill(s["robots"][0]["links"][0]["hulls"], 0.012, f)
    (d / "scene.yaml").write_text(yaml.safe_dump(s, sort_keys=False, default_flow_style=None, width=200))
    (d / "task.yaml").write_text(task)
    subprocess.run(["nice", "-n", "5", bin_, "optimize", str(d / "task.yaml"), "--out", str(d / "o"),
                    "--iters", "0", "--force", "-q"], check=True)
    l0, _, g, h = row(d / "o")
    print(f"| {f:.2f} | {l0:.4e} | {g['grasped']} | {g['max_drift']:.3f} | {g['rise']:.4f} | {h} |")
PY
# The right leg seen along the arm: initial, drilled (scene_hole.yaml), the
# design alone (trust region, Adam); copy it to docs/ to update the README's.
"$PY" tools/gen/picture_single_jaw_cross.py robots/single_jaw_cross/scene.yaml \
  robots/single_jaw_cross/scene_hole.yaml "$OUT/design_alone/scenes/scene.yaml" \
  "$OUT/design_alone_adam/scenes/scene.yaml" --out "$OUT/single_jaw_cross.png"
