#!/usr/bin/env python3
"""How much a co-design changed the blocks of its designed links: per-block
volumes (convex hulls by scipy's Qhull; a hull enclosing no volume counts
0) and vertex displacements, initial scene against optimized scene.

    .venv/bin/python tools/gen/design_change.py INITIAL.yaml OPTIMIZED.yaml LINK [LINK ...] [--bound B]

Prints, per link: blocks, total volume before → after, the smallest
after/before volume ratio, how many blocks changed volume by more than 10 %
and 50 %, the largest and median vertex displacement, and (with --bound)
the fraction of vertex coordinates at their bound (within 1e-9 m).
"""
import argparse
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial import ConvexHull
from scipy.spatial import QhullError


def link_hulls(scene, name):
    robot, link = name.split("/")
    r = next(r for r in scene["robots"] if r["name"] == robot)
    return [np.array(h["vertices"], float) for h in next(l for l in r["links"] if l["name"] == link)["hulls"]]


def volume(v):
    try:
        return ConvexHull(v).volume
    except QhullError:
        return 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("initial")
    ap.add_argument("optimized")
    ap.add_argument("links", nargs="+")
    ap.add_argument("--bound", type=float)
    a = ap.parse_args()
    s0 = yaml.safe_load(Path(a.initial).read_text())
    s1 = yaml.safe_load(Path(a.optimized).read_text())
    for name in a.links:
        h0, h1 = link_hulls(s0, name), link_hulls(s1, name)
        v0 = np.array([volume(h) for h in h0])
        v1 = np.array([volume(h) for h in h1])
        ratio = v1 / v0
        disp = np.concatenate([np.linalg.norm(b - c, axis=1) for b, c in zip(h0, h1)])
        line = (f"{name}: {len(h0)} blocks, volume {v0.sum() * 1e6:.2f} → {v1.sum() * 1e6:.2f} cm³, "
                f"smallest ratio {ratio.min():.3f} (block {ratio.argmin()}), "
                f"|Δvol| > 10 %: {(abs(ratio - 1) > 0.1).sum()}, > 50 %: {(abs(ratio - 1) > 0.5).sum()}, "
                f"vertex displacement max {disp.max() * 1e3:.2f} mm, median {np.median(disp) * 1e3:.3f} mm")
        if a.bound:
            d = np.concatenate([np.abs(b - c).ravel() for b, c in zip(h0, h1)])
            line += f", coordinates at the bound {np.mean(d >= a.bound - 1e-9):.3f}"
        print(line)


if __name__ == "__main__":
    main()
