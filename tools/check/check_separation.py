#!/usr/bin/env python3
"""Independent non-interpenetration check of an `sdrs simulate --export DIR` run.

Reads DIR/hulls.json (every link's hulls in its frame, and the link pairs that
never interact) and DIR/poses.csv (every link pose per step), rebuilds each
hull as a triangle mesh (scipy's Qhull) and asks FCL (python-fcl) for the
distance of every interacting hull pair at every step. Pairs whose world
bounding boxes are apart are separated without asking FCL (a box gap is a
lower bound of the distance). Prints a JSON report and exits 1 if any pair is
at distance <= 0 (touching or overlapping), 2 on bad input.

If DIR/surfaces.json exists (written by `sdrs simulate --contact ipc --export`
when `contact.ipc.surface: source`), the links it lists are checked with those
triangle meshes (possibly non-convex) instead of their hulls: mesh pairs use
FCL's BVH–BVH distance (OBBRSS), and since a surface distance cannot see one
solid inside another, a pair with a positive distance whose world boxes nest
is also tested for containment (generalized winding number of one vertex).

Several DIRs may be given (one Python start for many exports): the report is
then a JSON list with one entry per DIR (its "dir" added), and the exit code
the worst of them.

Usage: check_separation.py DIR [DIR ...] [--every K]
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


def bvh(v, tri):
    """An FCL triangle-mesh (OBBRSS BVH) model."""
    m = fcl.BVHModel()
    m.beginModel(len(v), len(tri))
    m.addSubModel(np.asarray(v, dtype=float), np.asarray(tri, dtype=np.int64))
    m.endModel()
    return m


def nested(lo_a, hi_a, lo_b, hi_b):
    """Box a lies inside box b."""
    return bool(np.all(lo_a >= lo_b) and np.all(hi_a <= hi_b))


def winding(x, tri, p):
    """Generalized winding number of the closed triangle mesh (x, tri) around p
    (1 inside an outward mesh, 0 outside; Van Oosterom & Strackee)."""
    a, b, c = x[tri[:, 0]] - p, x[tri[:, 1]] - p, x[tri[:, 2]] - p
    la, lb, lc = (np.linalg.norm(u, axis=1) for u in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la \
        + np.einsum("ij,ij->i", c, a) * lb
    return abs(float(np.sum(2.0 * np.arctan2(num, den))) / (4.0 * np.pi))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path, nargs="+")
    ap.add_argument("--every", type=int, default=1, help="check every K-th step (default 1)")
    args = ap.parse_args()
    results = [check(d, args.every) for d in args.dir]
    if len(results) == 1:
        print(json.dumps(results[0][1], indent=2))
    else:
        print(json.dumps([{"dir": str(d), **r} for d, (_, r) in zip(args.dir, results)], indent=2))
    return max(code for code, _ in results)


def check(dir: Path, every: int) -> tuple[int, dict]:
    """The check of one export: (exit code, report)."""
    try:
        hulls, poses = load(dir)
    except (OSError, KeyError, ValueError) as e:
        print(f"{dir}: cannot read the export: {e}", file=sys.stderr)
        return 2, {"error": f"cannot read the export: {e}"}
    excluded = {tuple(sorted(p)) for p in hulls["excluded_pairs"]}
    surfaces = {}
    if (dir / "surfaces.json").exists():
        try:
            for s in json.loads((dir / "surfaces.json").read_text())["links"]:
                surfaces[int(s["link"])] = (np.asarray(s["vertices"], dtype=float),
                                            np.asarray(s["triangles"], dtype=np.int64))
        except (OSError, KeyError, ValueError) as e:
            print(f"{dir}: cannot read surfaces.json: {e}", file=sys.stderr)
            return 2, {"error": f"cannot read surfaces.json: {e}"}
    # Local geometry: FCL convex shapes from Qhull triangles, and BVH models
    # (for pairs with a source-mesh surface).
    items = []  # (link, hull index (-1: surface mesh), local vertices, triangles, fcl convex, fcl BVH)
    for li, link in enumerate(hulls["links"]):
        if li in surfaces:
            v, tri = surfaces[li]
            items.append((li, -1, v, tri, None, bvh(v, tri)))
            continue
        for hi, verts in enumerate(link["hulls"]):
            v = np.asarray(verts, dtype=float)
            tri = ConvexHull(v).simplices
            faces = np.hstack([np.full((len(tri), 1), 3), tri]).ravel()
            items.append((li, hi, v, tri, fcl.Convex(v, len(tri), faces), bvh(v, tri)))
    pairs = [(a, b) for a in range(len(items)) for b in range(a + 1, len(items))
             if items[a][0] != items[b][0] and tuple(sorted((items[a][0], items[b][0]))) not in excluded]
    request = fcl.DistanceRequest(enable_nearest_points=False)
    min_d, min_at, checked, fcl_calls, mesh_calls, bad = np.inf, None, 0, 0, 0, []
    for k in sorted(poses)[::every]:
        world = []
        for li, hi, v, tri, geom, mesh in items:
            r, t = poses[k][li]
            x = v @ r.T + t
            tf = fcl.Transform(r, t)
            world.append((x.min(axis=0), x.max(axis=0),
                          geom and fcl.CollisionObject(geom, tf), fcl.CollisionObject(mesh, tf), x, tri))
        step_min = np.inf
        for a, b in pairs:
            lo_a, hi_a, oa, ma, xa, ta = world[a]
            lo_b, hi_b, ob, mb, xb, tb = world[b]
            gap = np.max(np.maximum(lo_b - hi_a, lo_a - hi_b))
            if gap > 0.05:
                d = gap  # boxes apart: a lower bound is enough
            elif items[a][1] >= 0 and items[b][1] >= 0:
                d = fcl.distance(oa, ob, request, fcl.DistanceResult())
                fcl_calls += 1
            else:
                d = fcl.distance(ma, mb, request, fcl.DistanceResult())
                fcl_calls += 1
                mesh_calls += 1
                if d > 0 and (nested(lo_a, hi_a, lo_b, hi_b) or nested(lo_b, hi_b, lo_a, hi_a)):
                    if winding(xb, tb, xa[0]) > 0.5 or winding(xa, ta, xb[0]) > 0.5:
                        d = 0.0  # one solid inside the other
            step_min = min(step_min, d)
            if d <= 0.0:
                bad.append({"step": k, "pair": [hulls["links"][items[a][0]]["name"], hulls["links"][items[b][0]]["name"]], "distance": d})
        checked += 1
        if step_min < min_d:
            min_d, min_at = step_min, k
    report = {"steps_checked": checked, "hull_pairs": len(pairs), "fcl_distance_calls": fcl_calls,
              "surface_links": sorted(surfaces), "mesh_distance_calls": mesh_calls,
              "min_distance": None if not np.isfinite(min_d) else float(min_d), "min_at_step": min_at,
              "violations": bad[:20], "violation_count": len(bad)}
    return (1 if bad else 0), report


if __name__ == "__main__":
    sys.exit(main())
