#!/usr/bin/env python3
"""Is a co-design's gain the shape or the optimization path? Runs the optimized
controller on the optimized links and on the initial links.

    .venv/bin/python tools/bench/swap_links.py TASK OPTIMIZED.yaml LINK [LINK ...] [--sdrs BIN] [--out DIR]

TASK is the task file (its scene is the initial design), OPTIMIZED.yaml the
run's `design.yaml` (a complete scene: optimized hulls and controller).
Writes DIR/optimized and DIR/initial_links: the optimized scene, and the same
scene with the listed links' `hulls` (and `mass` entries) replaced by the
initial scene's, each with a copy of the task pointing at it; evaluates
each with `sdrs optimize TASK --design off --iters 0` (one forward pass,
the task's loss and metrics) and prints loss, distance and upright at H.
"""
import argparse
import json
import subprocess
from pathlib import Path

import yaml


def links(scene):
    return {(r["name"], l["name"]): l for r in scene["robots"] for l in r["links"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("task", type=Path)
    ap.add_argument("optimized", type=Path)
    ap.add_argument("links", nargs="+", help="robot/link")
    ap.add_argument("--sdrs", default="target/release/sdrs")
    ap.add_argument("--out", type=Path, default=Path("out/swap_links"))
    a = ap.parse_args()
    task = yaml.safe_load(a.task.read_text())
    initial = yaml.safe_load((a.task.parent / task["scene"]).read_text())
    opt = yaml.safe_load(a.optimized.read_text())
    swapped = yaml.safe_load(a.optimized.read_text())
    li, ls = links(initial), links(swapped)
    for name in a.links:
        key = tuple(name.split("/"))
        for field in ("hulls", "mass"):
            if field in li[key]:
                ls[key][field] = li[key][field]
            else:
                ls[key].pop(field, None)
    print("| links | loss | distance (m) | upright at H | first fall (s) |")
    print("|---|---|---|---|---|")
    for label, scene in (("optimized", opt), ("initial_links", swapped)):
        d = a.out / label
        d.mkdir(parents=True, exist_ok=True)
        (d / "scene.yaml").write_text(yaml.safe_dump(scene, sort_keys=False))
        (d / "task.yaml").write_text(yaml.safe_dump(dict(task, scene="scene.yaml"), sort_keys=False))
        subprocess.run([a.sdrs, "optimize", str(d / "task.yaml"), "--design", "off", "--iters", "0",
                        "--out", str(d / "run"), "--force", "-q"], check=True, capture_output=True)
        s = json.loads((d / "run/summary.json").read_text())
        m = s["extra"]["metrics"]["initial"]
        fall = m["first_fall_time"]
        print(f"| {label} | {s['initial_loss']:.3f} | {m['distance']:.3f} | "
              f"{'yes' if m['upright_at_horizon'] else 'no'} | {'—' if fall is None else f'{fall:.2f}'} |")


if __name__ == "__main__":
    main()
