#!/usr/bin/env python3
"""Independent convex-hull check for tests/import_hull.rs.

Reads a JSON file {"cases": [{"name", "points": [[x,y,z],...],
"volume": our hull volume or null, "tol": relative tolerance}]} and computes
each point set's convex-hull volume with Qhull (scipy.spatial.ConvexHull,
options "Qt" only, no joggle). A case with "volume": null is expected to have
no hull with volume (flat input): it passes when Qhull also refuses it or
finds a volume below 1e-12 x extent^3. Prints one line per case; exits 1 if
any case disagrees.
"""
import json
import sys

import numpy as np
from scipy.spatial import ConvexHull, QhullError


def main():
    data = json.load(open(sys.argv[1]))
    bad = 0
    for c in data["cases"]:
        p = np.asarray(c["points"], dtype=float)
        ext = float(np.linalg.norm(p.max(0) - p.min(0)))
        try:
            q = ConvexHull(p, qhull_options="Qt").volume
        except QhullError:
            q = None
        ours = c["volume"]
        if ours is None:
            ok = q is None or q <= 1e-12 * ext**3
        else:
            ok = q is not None and abs(ours - q) <= c["tol"] * q
        rel = None if (ours is None or q is None) else abs(ours - q) / q
        print(f"{c['name']}: ours {ours} qhull {q} rel {rel} {'ok' if ok else 'MISMATCH'}")
        bad += not ok
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
