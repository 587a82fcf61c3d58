"""A test fixture from an `sdrs optimize` run: the coordinates of its best
iterate that differ from its start, as [index, start value, best value].

    python tools/gen/design_fixture.py START/checkpoint.json RUN/checkpoint.json OUT.json --about "..." [--seed S] [--eta ETA]

START is the run's start (`sdrs optimize … --iters 0` with the same task
and seed: its checkpoint's design is the start), RUN the run itself. The
values are written with Python's shortest round-trip repr, so a test
rebuilds the design bitwise. Refuses to overwrite OUT.
"""
import argparse
import json
import sys
from pathlib import Path


def design(ckpt, best):
    s = json.loads(Path(ckpt).read_text())["state"]
    d = s["best"]["design"] if best else s["design"]
    return d[0]  # nalgebra's DVector: [data, rows, cols]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("start")
    ap.add_argument("run")
    ap.add_argument("out")
    ap.add_argument("--about", required=True)
    ap.add_argument("--seed", type=int)
    ap.add_argument("--eta", type=float)
    a = ap.parse_args()
    out = Path(a.out)
    if out.exists():
        sys.exit(f"{out}: exists, not overwritten")
    d0, run = design(a.start, False), json.loads(Path(a.run).read_text())["state"]
    d1 = run["best"]["design"][0]
    if len(d0) != len(d1):
        sys.exit(f"{a.start} has {len(d0)} design variables, {a.run} {len(d1)}")
    moved = [[i, x, y] for i, (x, y) in enumerate(zip(d0, d1)) if x != y]
    fx = {"about": a.about, "iteration": run["best"]["iter"], "loss": run["best"]["loss"],
          "variables": len(d0), "seed": a.seed, "design_init_noise": a.eta, "moved": moved}
    out.write_text(json.dumps(fx) + "\n")
    print(f"{out}: {len(moved)} of {len(d0)} coordinates moved, best iterate {fx['iteration']}, loss {fx['loss']:.6e}")


if __name__ == "__main__":
    main()
