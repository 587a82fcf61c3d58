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


POSE_COLUMNS = ["a00", "a10", "a20", "a01", "a11", "a21", "a02", "a12", "a22", "t0", "t1", "t2"]


def load(dirpath: Path, every: int = 1):
    """hulls.json, and the link poses of every `every`-th step of poses.csv
    ({step: {link: (R, t)}}). Only the checked steps' numbers are parsed
    (a check of every 20th step spent most of its time parsing the others)."""
    hulls = json.loads((dirpath / "hulls.json").read_text())
    rows = {}
    with open(dirpath / "poses.csv", newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        step, link = header.index("step"), header.index("link")
        cols = [header.index(c) for c in POSE_COLUMNS]
        for row in reader:
            rows.setdefault(int(row[step]), {})[int(row[link])] = row
    poses = {}
    for k in sorted(rows)[::every]:
        for li, row in rows[k].items():
            a = np.array([float(row[c]) for c in cols])
            # column-major 3x4 [R | t]
            poses.setdefault(k, {})[li] = (a[:9].reshape(3, 3, order="F"), a[9:])
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


def read_surfaces(dir: Path) -> dict:
    """surfaces.json's meshes by link ({} when the export has none)."""
    surfaces = {}
    if (dir / "surfaces.json").exists():
        for s in json.loads((dir / "surfaces.json").read_text())["links"]:
            surfaces[int(s["link"])] = (np.asarray(s["vertices"], dtype=float),
                                        np.asarray(s["triangles"], dtype=np.int64))
    return surfaces


class Item:
    """A hull, or a link's source-mesh surface, in its link's frame. Its
    triangles (Qhull's, for a hull) and FCL models are made when a near pair
    first needs them: most hulls of a robot never come within 0.05 m of
    another's (pybullet_data's 186 exports: half the check's time went to
    making them all)."""

    def __init__(self, link: int, hull: int, v, tri=None):
        self.link, self.hull, self.v, self._tri = link, hull, v, tri
        self._convex, self._mesh = None, None

    def tri(self):
        if self._tri is None:
            self._tri = ConvexHull(self.v).simplices
        return self._tri

    def convex(self):
        """FCL's convex shape of a hull (None for a surface)."""
        if self._convex is None and self.hull >= 0:
            tri = self.tri()
            faces = np.hstack([np.full((len(tri), 1), 3), tri]).ravel()
            self._convex = fcl.Convex(self.v, len(tri), faces)
        return self._convex

    def mesh(self):
        """FCL's BVH model of the triangles (for pairs with a surface)."""
        if self._mesh is None:
            self._mesh = bvh(self.v, self.tri())
        return self._mesh


def geometry(hulls: dict, surfaces: dict) -> list:
    """Every hull of every link, or the link's surface mesh when it has one."""
    items = []
    for li, link in enumerate(hulls["links"]):
        if li in surfaces:
            v, tri = surfaces[li]
            items.append(Item(li, -1, v, tri))
            continue
        for hi, verts in enumerate(link["hulls"]):
            items.append(Item(li, hi, np.asarray(verts, dtype=float)))
    return items


class Step:
    """One step's world geometry: every item's vertices and bounding box,
    and its FCL collision objects, made when a pair first needs them."""

    def __init__(self, items: list, pose: dict):
        self.items, self.x, self.objects = items, [], {}
        for it in items:
            r, t = pose[it.link]
            self.x.append(it.v @ r.T + t)
        self.lo = np.array([x.min(axis=0) for x in self.x]).reshape(-1, 3)
        self.hi = np.array([x.max(axis=0) for x in self.x]).reshape(-1, 3)
        self.pose = pose

    def convex_object(self, i: int):
        """Item `i`'s FCL convex collision object at this step."""
        if ("c", i) not in self.objects:
            it = self.items[i]
            self.objects["c", i] = fcl.CollisionObject(it.convex(), fcl.Transform(*self.pose[it.link]))
        return self.objects["c", i]

    def mesh_object(self, i: int):
        """Item `i`'s FCL BVH collision object at this step."""
        if ("m", i) not in self.objects:
            it = self.items[i]
            self.objects["m", i] = fcl.CollisionObject(it.mesh(), fcl.Transform(*self.pose[it.link]))
        return self.objects["m", i]


def near_distance(step: Step, a: int, b: int, request, counts: list) -> float:
    """FCL's distance of items `a` and `b` (whose boxes are within 0.05 m);
    `counts` = [FCL calls, mesh calls], updated."""
    items = step.items
    counts[0] += 1
    if items[a].hull >= 0 and items[b].hull >= 0:
        return fcl.distance(step.convex_object(a), step.convex_object(b), request, fcl.DistanceResult())
    counts[1] += 1
    d = fcl.distance(step.mesh_object(a), step.mesh_object(b), request, fcl.DistanceResult())
    lo_a, hi_a, lo_b, hi_b = step.lo[a], step.hi[a], step.lo[b], step.hi[b]
    if d > 0 and (nested(lo_a, hi_a, lo_b, hi_b) or nested(lo_b, hi_b, lo_a, hi_a)):
        xa, ta, xb, tb = step.x[a], items[a].tri(), step.x[b], items[b].tri()
        if winding(xb, tb, xa[0]) > 0.5 or winding(xa, ta, xb[0]) > 0.5:
            d = 0.0  # one solid inside the other
    return d


def check(dir: Path, every: int) -> tuple[int, dict]:
    """The check of one export: (exit code, report). Pairs whose world boxes
    are more than 0.05 m apart take the box gap as their distance; their
    gaps are computed for all pairs at once (the same differences and
    maxima as pair by pair), and FCL is asked about the others only."""
    try:
        hulls, poses = load(dir, every)
    except (OSError, KeyError, ValueError) as e:
        print(f"{dir}: cannot read the export: {e}", file=sys.stderr)
        return 2, {"error": f"cannot read the export: {e}"}
    excluded = {tuple(sorted(p)) for p in hulls["excluded_pairs"]}
    try:
        surfaces = read_surfaces(dir)
    except (OSError, KeyError, ValueError) as e:
        print(f"{dir}: cannot read surfaces.json: {e}", file=sys.stderr)
        return 2, {"error": f"cannot read surfaces.json: {e}"}
    items = geometry(hulls, surfaces)
    pairs = [(a, b) for a in range(len(items)) for b in range(a + 1, len(items))
             if items[a].link != items[b].link and tuple(sorted((items[a].link, items[b].link))) not in excluded]
    ia = np.array([a for a, _ in pairs], dtype=np.int64)
    ib = np.array([b for _, b in pairs], dtype=np.int64)
    request = fcl.DistanceRequest(enable_nearest_points=False)
    min_d, min_at, checked, counts, bad = np.inf, None, 0, [0, 0], []
    for k in sorted(poses):
        step = Step(items, poses[k])
        step_min = np.inf
        if pairs:
            gap = np.max(np.maximum(step.lo[ib] - step.hi[ia], step.lo[ia] - step.hi[ib]), axis=1)
            far = gap > 0.05  # boxes apart: a lower bound is enough
            if far.any():
                step_min = min(step_min, gap[far].min())
            for p in np.flatnonzero(~far):
                a, b = pairs[p]
                d = near_distance(step, a, b, request, counts)
                step_min = min(step_min, d)
                if d <= 0.0:
                    bad.append({"step": k, "pair": [hulls["links"][items[a].link]["name"], hulls["links"][items[b].link]["name"]], "distance": d})
        checked += 1
        if step_min < min_d:
            min_d, min_at = step_min, k
    report = {"steps_checked": checked, "hull_pairs": len(pairs), "fcl_distance_calls": counts[0],
              "surface_links": sorted(surfaces), "mesh_distance_calls": counts[1],
              "min_distance": None if not np.isfinite(min_d) else float(min_d), "min_at_step": min_at,
              "violations": bad[:20], "violation_count": len(bad)}
    return (1 if bad else 0), report


if __name__ == "__main__":
    sys.exit(main())
