#!/usr/bin/env python3
"""Mass properties of convex hulls by trimesh, for the `solid` mass-model test.

Usage: check_mass_trimesh.py HULLS.json
HULLS.json: {"hulls": [{"vertices": [[x, y, z], ...], "density": rho}, ...]}
Prints JSON {"hulls": [{"mass", "volume", "com": [3], "inertia": [[3]x3]}]} with
trimesh's `mass_properties` of the convex hull of each vertex list (inertia
about the centre of mass, kg m²). Exit code 3 when trimesh is missing.
"""
import json
import sys

try:
    import numpy as np
    import trimesh
except ImportError as e:  # pragma: no cover
    print(f"missing package: {e}", file=sys.stderr)
    sys.exit(3)


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    with open(sys.argv[1]) as f:
        spec = json.load(f)
    out = []
    for i, h in enumerate(spec["hulls"]):
        pts = np.asarray(h["vertices"], dtype=float)
        mesh = trimesh.convex.convex_hull(pts)
        if not mesh.is_watertight:
            print(f"hull {i}: trimesh's hull is not watertight", file=sys.stderr)
            sys.exit(1)
        mesh.density = float(h["density"])
        p = mesh.mass_properties
        out.append(
            {
                "mass": float(p["mass"]),
                "volume": float(p["volume"]),
                "com": [float(v) for v in p["center_mass"]],
                "inertia": [[float(v) for v in row] for row in p["inertia"]],
            }
        )
    print(json.dumps({"hulls": out}))


if __name__ == "__main__":
    main()
