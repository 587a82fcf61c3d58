#!/usr/bin/env python3
"""Approximate convex decomposition with CoACD (called by `sdrs import --decomposer coacd`).

Usage: coacd_decompose.py MESH OUT.json [--threshold T] [--max-hulls N] [--resolution R] [--seed S]

Writes {"hulls": [{"vertices": [[x, y, z], ...]}, ...]} to OUT.json.
Exit code 3 when a required package is missing (sdrs then prints the install command).
"""
import argparse
import json
import sys

try:
    import numpy as np
    import trimesh
    import coacd
except ImportError as e:  # pragma: no cover - reported to the caller
    print(f"missing Python package: {e.name} (needed by tools/helpers/coacd_decompose.py)", file=sys.stderr)
    sys.exit(3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--threshold", type=float, default=0.05)
    ap.add_argument("--max-hulls", type=int, default=-1)
    ap.add_argument("--resolution", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--extrude-margin", type=float, default=0.01,
                    help="CoACD extrudes neighbouring parts into each other by this much (relative) "
                         "so they overlap; 0 disables (parts then only nearly touch)")
    a = ap.parse_args()
    mesh = trimesh.load(a.mesh, force="mesh", process=False)
    if len(mesh.faces) == 0:
        print(f"{a.mesh}: empty mesh", file=sys.stderr)
        return 1
    coacd.set_log_level("error")
    cm = coacd.Mesh(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=int))
    parts = coacd.run_coacd(
        cm,
        threshold=a.threshold,
        max_convex_hull=a.max_hulls if a.max_hulls > 0 else -1,
        resolution=a.resolution,
        seed=a.seed,
        extrude=a.extrude_margin > 0,
        extrude_margin=max(a.extrude_margin, 1e-6),
    )
    hulls = [{"vertices": np.asarray(v, dtype=float).tolist()} for v, _f in parts]
    with open(a.out, "w") as f:
        json.dump({"hulls": hulls}, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
