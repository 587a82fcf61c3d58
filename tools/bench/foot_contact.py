#!/usr/bin/env python3
"""Which design vertices ever come within the contact distance of the ground
along a trajectory (`sdrs simulate DESIGN.yaml --export DIR`).

    .venv/bin/python tools/bench/foot_contact.py DIR LINK [LINK ...] [--ground NAME] [--s 0.01]

The ground is the link named --ground (default: the link whose name contains
"ground"); its top face is the hull face whose outward world normal is
closest to +z at step 0 (a static ground). For every vertex of the listed
links' hulls (link frame, hulls.json; poses.csv gives the world pose per
step) the signed height above that face's plane, h = n·x − n·p, is computed
at every step. The pair's contact potential is zero unless the hulls are
closer than a = 2s/(1 − s) (DESIGN.md: the separating plane sits between
them and each side's vertices feel the barrier P_s within s of the plane;
s = 0.01 m in the locomotion scenes, a = 0.0202 m), so only vertices with
h < a can receive a direct contact gradient (an upper bound: the nearest
vertices of a hull take most of it). Prints per link: vertices, vertices
ever within a, the largest count within a at one step, the share of steps
with any vertex within a, and the lowest h reached (m).
"""
import argparse
import csv
import json
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull


def poses(path):
    out = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            a = np.array([float(row[c]) for c in
                          ["a00", "a10", "a20", "a01", "a11", "a21", "a02", "a12", "a22", "t0", "t1", "t2"]])
            out.setdefault(int(row["step"]), {})[int(row["link"])] = (a[:9].reshape(3, 3, order="F"), a[9:])
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir", type=Path)
    ap.add_argument("links", nargs="+")
    ap.add_argument("--ground")
    ap.add_argument("--s", type=float, default=0.01)
    a = ap.parse_args()
    hulls = json.loads((a.dir / "hulls.json").read_text())
    names = [l["name"] for l in hulls["links"]]
    g = names.index(a.ground) if a.ground else next(i for i, n in enumerate(names) if "ground" in n)
    P = poses(a.dir / "poses.csv")
    steps = sorted(P)
    r, t = P[steps[0]][g]
    gv = np.vstack([np.asarray(h, float) for h in hulls["links"][g]["hulls"]]) @ r.T + t
    hull = ConvexHull(gv)
    eq = hull.equations[np.argmax(hull.equations[:, 2])]  # n·x + c <= 0 inside
    n, c = eq[:3], eq[3]
    report = {"ground": names[g], "normal": n.tolist(), "s": a.s, "steps": len(steps), "links": {}}
    for name in a.links:
        li = next(i for i, m in enumerate(names) if m == name or m.endswith("/" + name) or name.endswith("/" + m))
        v = np.unique(np.vstack([np.asarray(h, float) for h in hulls["links"][li]["hulls"]]), axis=0)
        heights = np.array([(v @ P[k][li][0].T + P[k][li][1]) @ n + c for k in steps])  # steps x vertices
        near = heights < 2 * a.s / (1 - a.s)
        report["links"][name] = {
            "vertices": int(v.shape[0]),
            "ever_within_a": int(near.any(axis=0).sum()),
            "max_within_a_at_one_step": int(near.sum(axis=1).max()),
            "share_of_steps_with_contact": float(near.any(axis=1).mean()),
            "lowest_height": float(heights.min()),
        }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
