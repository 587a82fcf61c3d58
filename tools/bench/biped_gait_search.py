#!/usr/bin/env python3
"""The biped's initial gait by a registered sampling search (issue 30, item 4;
notes/locomotion-feet-and-radius.md §7).

    .venv/bin/python tools/bench/biped_gait_search.py [--sdrs target/release/sdrs] [--out out/biped_gait] [--workers 2]

Family: `biped_gait` in tools/gen/make_locomotion_scenes.py (7 parameters:
f, A_h, A_k, K0, pk, A_r, pr; legs in anti-phase, soles parallel to the
torso). Search, fixed before the first run (2026-11-30): on the flat soles of
tools/bench/biped_standing_probe.py (a design inside the task's bound),
400 uniform samples in RANGES (numpy default_rng(0)), then 200 Gaussian
samples around the best (σ = 10 % of each range, clipped; default_rng(1)).
Each sample is one forward pass of robots/biped/task.yaml (`sdrs optimize
--design off --iters 0`: the task's loss and metrics). Score: the distance
along +y among samples upright at H (ties: the lower loss). Then the chosen
gait on the imported feet (the paper's premise: it must fall there).
Writes OUT/results.jsonl (every sample) and OUT/chosen.json; prints the
chosen parameters, which the generator holds as BIPED_GAIT.
"""
import argparse
import copy
import json
import math
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools/bench"))
sys.path.insert(0, str(ROOT / "tools/gen"))
from biped_standing_probe import flatten  # noqa: E402
from make_locomotion_scenes import biped_gait  # noqa: E402

NAMES = ["f", "A_h", "A_k", "K0", "pk", "A_r", "pr"]
LO = np.array([0.5, 0.0, 0.0, 0.0, -math.pi, 0.0, -math.pi])
HI = np.array([2.0, 0.4, 0.5, 0.4, math.pi, 0.15, math.pi])


def evaluate(a, tag, p, feet):
    """One forward pass of the task with gait `p` on `feet` ('flat' or 'imported')."""
    s = yaml.safe_load((ROOT / "robots/biped/scene.yaml").read_text())
    task = yaml.safe_load((ROOT / "robots/biped/task.yaml").read_text())
    if feet == "flat":
        flatten(s)
    targets = s["robots"][0]["controller"]["targets"]
    new = biped_gait(p)
    s["robots"][0]["controller"]["targets"] = {k: new[k] for k in targets}
    d = Path(a.out) / "runs" / tag
    d.mkdir(parents=True, exist_ok=True)
    (d / "scene.yaml").write_text(yaml.safe_dump(s, sort_keys=False))
    (d / "task.yaml").write_text(yaml.safe_dump(dict(copy.deepcopy(task), scene="scene.yaml"), sort_keys=False))
    r = subprocess.run([a.sdrs, "optimize", str(d / "task.yaml"), "--design", "off", "--iters", "0",
                        "--out", str(d / "run"), "--force", "-q"], capture_output=True, text=True)
    row = {"tag": tag, "p": [float(v) for v in p], "feet": feet}
    if r.returncode != 0:
        return dict(row, error=r.stderr[-300:])
    sm = json.loads((d / "run/summary.json").read_text())
    return dict(row, loss=sm["final_loss"], metrics=sm["extra"]["metrics"]["final"])


def score(r):
    m = r.get("metrics", {})
    if "error" in r or not m.get("upright_at_horizon"):
        return (-math.inf, 0.0)
    return (m["distance"], -r["loss"])


def batch(a, prefix, samples):
    with ThreadPoolExecutor(a.workers) as ex:
        return list(ex.map(lambda ip: evaluate(a, f"{prefix}{ip[0]:03d}", ip[1], "flat"),
                           enumerate(samples)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sdrs", default=str(ROOT / "target/release/sdrs"))
    ap.add_argument("--out", default="out/biped_gait")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    u = np.random.default_rng(0).uniform(size=(400, 7))
    rows = batch(a, "u", LO + u * (HI - LO))
    best = max(rows, key=score)
    g = np.random.default_rng(1).normal(size=(200, 7)) * 0.1 * (HI - LO) + np.array(best["p"])
    rows += batch(a, "g", np.clip(g, LO, HI))
    with open(out / "results.jsonl", "w") as fh:
        for r in rows:
            fh.write(json.dumps(r) + "\n")
    best = max(rows, key=score)
    upright = sum(score(r)[0] > -math.inf for r in rows)
    check = evaluate(a, "chosen_imported", np.array(best["p"]), "imported")
    (out / "chosen.json").write_text(json.dumps({"flat": best, "imported": check}, indent=1))
    print(f"upright at H on flat soles: {upright} of {len(rows)}")
    print("chosen:", ", ".join(f"{n} {v:.6g}" for n, v in zip(NAMES, best["p"])))
    fm, im = best["metrics"], check.get("metrics", {})
    print(f"flat soles: distance {fm['distance']:.3f} m, loss {best['loss']:.4g}, upright at H")
    print(f"imported feet: distance {im.get('distance', float('nan')):.3f} m, "
          f"upright at H {im.get('upright_at_horizon')}, first fall {im.get('first_fall_time')} s")


if __name__ == "__main__":
    main()
