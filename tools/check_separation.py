#!/usr/bin/env python3
"""Independent non-interpenetration check of an `sdrs simulate --export DIR` run.

Reads DIR/hulls.json (every link's hulls in its frame, and the link pairs that
never interact) and DIR/poses.csv (every link pose per step), rebuilds each
hull as a triangle mesh (scipy's Qhull) and asks FCL (python-fcl) for the
distance of every interacting hull pair at every step. Pairs whose world
bounding boxes are apart are separated without asking FCL (a box gap is a
lower bound of the distance). Prints a JSON report and exits 1 if any pair is
at distance <= 0 (touching or overlapping), 2 on bad input.

Usage: check_separation.py DIR [--every K]
"""
import argparse
import csv
import json
import sys
from pathlib import Path

import fcl
import numpy as np
from scipy.spatial import ConvexHull


def load(dirpath: Path):
    hulls = json.loads((dirpath / "hulls.json").read_text())
    poses = {}
    with open(dirpath / "poses.csv", newline="") as f:
        for row in csv.DictReader(f):
            k, link = int(row["step"]), int(row["link"])
            a = np.array([float(row[c]) for c in
                          ["a00", "a10", "a20", "a01", "a11", "a21", "a02", "a12", "a22", "t0", "t1", "t2"]])
            # column-major 3x4 [R | t]
            poses.setdefault(k, {})[link] = (a[:9].reshape(3, 3, order="F"), a[9:])
    return hulls, poses


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path)
    ap.add_argument("--every", type=int, default=1, help="check every K-th step (default 1)")
    args = ap.parse_args()
    try:
        hulls, poses = load(args.dir)
    except (OSError, KeyError, ValueError) as e:
        print(f"{args.dir}: cannot read the export: {e}", file=sys.stderr)
        return 2
    excluded = {tuple(sorted(p)) for p in hulls["excluded_pairs"]}
    # Local geometry: FCL convex shapes from Qhull triangles.
    items = []  # (link, hull index, local vertices, fcl geometry)
    for li, link in enumerate(hulls["links"]):
        for hi, verts in enumerate(link["hulls"]):
            v = np.asarray(verts, dtype=float)
            tri = ConvexHull(v).simplices
            faces = np.hstack([np.full((len(tri), 1), 3), tri]).ravel()
            items.append((li, hi, v, fcl.Convex(v, len(tri), faces)))
    pairs = [(a, b) for a in range(len(items)) for b in range(a + 1, len(items))
             if items[a][0] != items[b][0] and tuple(sorted((items[a][0], items[b][0]))) not in excluded]
    request = fcl.DistanceRequest(enable_nearest_points=False)
    min_d, min_at, checked, fcl_calls, bad = np.inf, None, 0, 0, []
    for k in sorted(poses)[:: args.every]:
        world = []
        for li, hi, v, geom in items:
            r, t = poses[k][li]
            x = v @ r.T + t
            world.append((x.min(axis=0), x.max(axis=0), fcl.CollisionObject(geom, fcl.Transform(r, t))))
        step_min = np.inf
        for a, b in pairs:
            lo_a, hi_a, oa = world[a]
            lo_b, hi_b, ob = world[b]
            gap = np.max(np.maximum(lo_b - hi_a, lo_a - hi_b))
            if gap > 0.05:
                d = gap  # boxes apart: a lower bound is enough
            else:
                d = fcl.distance(oa, ob, request, fcl.DistanceResult())
                fcl_calls += 1
            step_min = min(step_min, d)
            if d <= 0.0:
                bad.append({"step": k, "pair": [hulls["links"][items[a][0]]["name"], hulls["links"][items[b][0]]["name"]], "distance": d})
        checked += 1
        if step_min < min_d:
            min_d, min_at = step_min, k
    report = {"steps_checked": checked, "hull_pairs": len(pairs), "fcl_distance_calls": fcl_calls,
              "min_distance": None if not np.isfinite(min_d) else float(min_d), "min_at_step": min_at,
              "violations": bad[:20], "violation_count": len(bad)}
    print(json.dumps(report, indent=2))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
