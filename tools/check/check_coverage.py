#!/usr/bin/env python3
"""Independent coverage check of an imported design (trimesh).

Usage: check_coverage.py SOURCE DESIGN.yaml [SOURCE DESIGN.yaml ...] [--samples N] [--tol-frac 0.02]
                         [--min 0.95] [--seed 0]

SOURCE is the imported .urdf (collision geometry, else visual; meshes and
box/cylinder/sphere primitives) or a bare .obj/.stl. For every source mesh,
N points are sampled uniformly on its surface (in the link frame); a point is
covered when it lies inside one of the link's hulls or within tol-frac of the
mesh's bounding-box diagonal of one. Prints a JSON report and exits 1 when a
link's coverage is below --min, 3 when a package is missing.

Several SOURCE DESIGN pairs may be given (one Python start for many
imports: the start, mostly trimesh's and scipy's imports, is most of a
small check's time): the report is then a JSON list with one entry per
pair (its "source" and "design" added; an entry that could not be
checked holds its "error"), and the exit code the worst of them.
"""
import argparse
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

try:
    import numpy as np
    import trimesh
    import yaml
    from scipy.spatial import ConvexHull
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e.name} (needed by tools/check/check_coverage.py)", file=sys.stderr)
    sys.exit(3)


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def resolve(urdf, filename):
    base = os.path.dirname(os.path.abspath(urdf))
    if filename.startswith("package://"):
        pkg, _, rel = filename[len("package://"):].partition("/")
        d = base
        while True:
            for cand in (os.path.join(d, pkg), d if os.path.basename(d) == pkg else None):
                if cand and os.path.isfile(os.path.join(cand, rel)):
                    return os.path.join(cand, rel)
            parent = os.path.dirname(d)
            if parent == d:
                break
            d = parent
        for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
            for cand in (os.path.join(entry, pkg), entry if os.path.basename(entry) == pkg else None):
                if cand and os.path.isfile(os.path.join(cand, rel)):
                    return os.path.join(cand, rel)
        raise FileNotFoundError(filename)
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    return filename if os.path.isabs(filename) else os.path.join(base, filename)


def floats(s, n, default):
    return [float(x) for x in s.split()] if s else [default] * n


def urdf_sources(urdf):
    """link name -> list of trimesh meshes in the link frame."""
    out = {}
    root = ET.parse(urdf).getroot()
    for link in root.findall("link"):
        elems = link.findall("collision") or link.findall("visual")
        meshes = []
        for el in elems:
            o = el.find("origin")
            xyz = floats(o.get("xyz") if o is not None else None, 3, 0.0)
            rpy = floats(o.get("rpy") if o is not None else None, 3, 0.0)
            g = el.find("geometry")
            m = None
            if g.find("mesh") is not None:
                me = g.find("mesh")
                m = trimesh.load(resolve(urdf, me.get("filename")), force="mesh", process=False)
                if me.get("scale"):
                    S = np.eye(4)
                    S[:3, :3] = np.diag(floats(me.get("scale"), 3, 1.0))
                    m.apply_transform(S)
            elif g.find("box") is not None:
                m = trimesh.creation.box(extents=floats(g.find("box").get("size"), 3, 0.0))
            elif g.find("cylinder") is not None:
                c = g.find("cylinder")
                m = trimesh.creation.cylinder(radius=float(c.get("radius")), height=float(c.get("length")), sections=64)
            elif g.find("sphere") is not None:
                m = trimesh.creation.icosphere(subdivisions=3, radius=float(g.find("sphere").get("radius")))
            if m is None:
                continue
            T = np.eye(4)
            T[:3, :3] = rpy_matrix(*rpy)
            T[:3, 3] = xyz
            m.apply_transform(T)
            meshes.append(m)
        if meshes:
            out[link.get("name")] = meshes
    return out


class _Loader(yaml.SafeLoader):
    """Reads scenes; also accepts the tagged hull form (`!vertices [...]`, `!box {...}`) of early files."""


_Loader.add_constructor("!vertices", lambda l, n: {"vertices": l.construct_sequence(n, deep=True)})
_Loader.add_constructor("!box", lambda l, n: {"box": l.construct_mapping(n, deep=True)})


def design_hulls(design):
    with open(design) as f:
        scene = yaml.load(f, Loader=_Loader)
    hulls = {}
    for robot in scene["robots"]:
        for link in robot["links"]:
            hs = []
            for h in link["hulls"]:
                if "vertices" in h:
                    hs.append(np.array(h["vertices"], dtype=float))
                else:
                    size = np.array(h["box"]["size"]) / 2
                    c = np.array(h["box"].get("center", [0, 0, 0]))
                    hs.append(np.array([[c[0] + sx * size[0], c[1] + sy * size[1], c[2] + sz * size[2]]
                                        for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]))
            hulls[link["name"]] = hs
    return hulls


def coverage(mesh, hulls, n, tol_frac, seed):
    pts, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    diag = float(np.linalg.norm(mesh.bounds[1] - mesh.bounds[0]))
    tol = tol_frac * diag
    dist = np.full(len(pts), np.inf)
    for v in hulls:
        ch = ConvexHull(v)
        A, b = ch.equations[:, :3], ch.equations[:, 3]
        viol = (pts @ A.T + b).max(axis=1)
        inside = viol <= 1e-12
        dist[inside] = 0.0
        todo = np.where(~inside & (viol <= tol) & (dist > tol))[0]
        if len(todo):
            hm = trimesh.Trimesh(vertices=v, faces=ch.simplices, process=False)
            _, d, _ = trimesh.proximity.closest_point(hm, pts[todo])
            dist[todo] = np.minimum(dist[todo], d)
    return float((dist <= tol).mean()), float(dist.max()), tol


def check(source, design, a):
    """The check of one pair: (exit code, report or None, error message or None)."""
    hulls = design_hulls(design)
    if source.lower().endswith((".urdf", ".xml")):
        sources = urdf_sources(source)
    else:
        if len(hulls) != 1:
            return 2, None, "a bare mesh source needs a one-link design"
        sources = {next(iter(hulls)): [trimesh.load(source, force="mesh", process=False)]}
    report = {}
    worst = 1.0
    for link, meshes in sources.items():
        if link not in hulls:
            return 1, None, f"link '{link}' has geometry in the source but is missing from the design"
        covs = [coverage(m, hulls[link], a.samples, a.tol_frac, a.seed + k) for k, m in enumerate(meshes)]
        c = min(x[0] for x in covs)
        report[link] = {"coverage": c, "max_distance": max(x[1] for x in covs), "meshes": len(meshes)}
        worst = min(worst, c)
    out = {"links": report, "min_coverage": worst, "threshold": a.min}
    if worst < a.min:
        bad = [l for l, r in report.items() if r["coverage"] < a.min]
        return 1, out, f"coverage below {a.min}: {', '.join(bad)}"
    return 0, out, None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", metavar="SOURCE DESIGN", help="source and design, pairwise")
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--tol-frac", type=float, default=0.02)
    ap.add_argument("--min", type=float, default=0.95)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    if len(a.files) % 2:
        ap.error("give SOURCE DESIGN pairs")
    pairs = list(zip(a.files[::2], a.files[1::2]))
    results = []
    for source, design in pairs:
        code, report, err = check(source, design, a)
        if err:
            print(err if len(pairs) == 1 else f"{source}: {err}", file=sys.stderr)
        results.append((code, report, err))
    if len(pairs) == 1:
        if results[0][1] is not None:
            print(json.dumps(results[0][1]))
    else:
        print(json.dumps([{"source": s, "design": d, **(r if r is not None else {"error": e})}
                          for (s, d), (_, r, e) in zip(pairs, results)]))
    return max(code for code, _, _ in results)


if __name__ == "__main__":
    sys.exit(main())
