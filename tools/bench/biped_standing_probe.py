#!/usr/bin/env python3
"""The biped's isolating evidence (issue 30, item 4): under the paper's loss
L = ||COM(theta^H) - (0, 3, 0)||^2 a design inside the task's design space
that stands for the whole horizon scores worse than a forward fall.

    .venv/bin/python tools/bench/biped_standing_probe.py [--sdrs target/release/sdrs] [--out out/biped_standing]

Builds, from robots/biped/scene.yaml and task.yaml:
  * flat feet: every vertex of the left_foot/right_foot hulls whose link-frame
    z lies within BAND (3 cm, chosen 2026-11-26 before the runs; 5 cm makes
    a hull coplanar) of that foot's lowest vertex is lowered to that lowest
    z (a move <= BAND < the task's 5 cm bound; vertices at the same position
    move the same way, so the ties between touching hulls hold);
  * held gait: every sine amplitude 0 (the PD holds the initial pose).
It evaluates (sdrs optimize --design off --iters 0, i.e. one forward pass
with the task's loss and metrics) four variants: {imported, flat} feet x
{held, initial gait}, and prints loss, distance, upright at H and the first
fall. Compare with the co-design run's forward fall
(sdrs optimize robots/biped/task.yaml --out DIR: loss 6.29 on 2026-11-26).
"""
import argparse
import copy
import json
import subprocess
from pathlib import Path

import yaml

BAND = 0.03
FEET = ("left_foot", "right_foot")


def flatten(scene):
    robot = scene["robots"][0]
    moved = 0
    for link in robot["links"]:
        if link["name"] not in FEET:
            continue
        zmin = min(v[2] for h in link["hulls"] for v in h["vertices"])
        for h in link["hulls"]:
            for v in h["vertices"]:
                if v[2] - zmin <= BAND and v[2] != zmin:
                    v[2] = zmin
                    moved += 1
    return moved


def hold(scene):
    for targets in scene["robots"][0]["controller"]["targets"].values():
        for t in targets:
            for term in t["terms"]:
                term["amplitude"] = 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sdrs", default="target/release/sdrs")
    ap.add_argument("--out", default="out/biped_standing")
    a = ap.parse_args()
    root = Path(__file__).resolve().parents[2]
    base = yaml.safe_load((root / "robots/biped/scene.yaml").read_text())
    task = yaml.safe_load((root / "robots/biped/task.yaml").read_text())
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for feet in ("imported", "flat"):
        for gait in ("held", "initial"):
            s = copy.deepcopy(base)
            moved = flatten(s) if feet == "flat" else 0
            if gait == "held":
                hold(s)
            d = out / f"{feet}_{gait}"
            d.mkdir(exist_ok=True)
            (d / "scene.yaml").write_text(yaml.safe_dump(s, sort_keys=False))
            t = dict(task, scene="scene.yaml")
            (d / "task.yaml").write_text(yaml.safe_dump(t, sort_keys=False))
            subprocess.run(
                [a.sdrs, "optimize", str(d / "task.yaml"), "--design", "off", "--iters", "0",
                 "--out", str(d / "run"), "--force", "-q"],
                check=True,
            )
            s_ = json.loads((d / "run/summary.json").read_text())
            rows.append((feet, moved, gait, s_["initial_loss"], s_["extra"]["metrics"]["initial"]))
    print("| feet | vertices moved | gait | loss | distance (m) | upright at H | first fall (s) |")
    print("|---|---|---|---|---|---|---|")
    for feet, moved, gait, loss, m in rows:
        fall = m["first_fall_time"]
        print(f"| {feet} | {moved} | {gait} | {loss:.3f} | {m['distance']:.3f} | "
              f"{'yes' if m['upright_at_horizon'] else 'no'} | {'—' if fall is None else f'{fall:.2f}'} |")
    print(f"(summary.json files under {out})")


if __name__ == "__main__":
    main()
