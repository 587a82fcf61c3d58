#!/usr/bin/env python3
"""SVG of one link's hulls from scene/design YAML files, side by side.

Usage: tools/gen/feet_figure.py LINK OUT.svg LABEL=SCENE.yaml [LABEL=SCENE.yaml ...]

For each file: the hulls of LINK (link frame) in two orthographic views,
side (x–z) and below (x–y), each hull's edges in its own colour (edges of
scipy's convex hull of the hull's vertices, coplanar facets' diagonals
dropped). Used for the feet pictures in notes/locomotion-feet-and-radius.md.
"""
import sys

import numpy as np
import yaml
from scipy.spatial import ConvexHull

COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]


def hulls_of(path, link):
    s = yaml.safe_load(open(path))
    for r in s["robots"]:
        for l in r["links"]:
            if l["name"] == link:
                return [np.array(h["vertices"], float) for h in l["hulls"]]
    raise SystemExit(f"{path}: no link {link}")


def edges(v):
    h = ConvexHull(v)
    out = set()
    for i, s in enumerate(h.simplices):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            e = tuple(sorted((s[a], s[b])))
            # keep the edge unless both facets sharing it are coplanar
            out.add(e)
    keep = []
    eq = h.equations
    for e in out:
        fs = [i for i, s in enumerate(h.simplices) if e[0] in s and e[1] in s]
        if len(fs) == 2 and np.allclose(eq[fs[0]], eq[fs[1]], atol=1e-9):
            continue
        keep.append(e)
    return keep


def main():
    link, out, items = sys.argv[1], sys.argv[2], [a.split("=", 1) for a in sys.argv[3:]]
    panels = [(lab, hulls_of(p, link)) for lab, p in items]
    allv = np.vstack([v for _, hs in panels for v in hs])
    lo, hi = allv.min(0), allv.max(0)
    span = (hi - lo).max()
    size, pad = 260.0, 30.0
    sc = size / span
    w = len(panels) * (size + pad) + pad
    hgt = 2 * (size + pad) + pad
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0f}" height="{hgt:.0f}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w:.0f}" height="{hgt:.0f}" fill="white"/>']
    for k, (lab, hs) in enumerate(panels):
        x0 = pad + k * (size + pad)
        nv = sum(len(v) for v in hs)
        svg.append(f'<text x="{x0:.1f}" y="18">{lab}: {len(hs)} hulls, {nv} vertices</text>')
        for row, (a, b, name) in enumerate(((0, 2, "side x–z"), (0, 1, "below x–y"))):
            y0 = pad + row * (size + pad)
            svg.append(f'<text x="{x0:.1f}" y="{y0 + size + 14:.1f}" fill="#666">{name}</text>')
            for j, v in enumerate(hs):
                col = COLORS[j % len(COLORS)]
                for e in edges(v):
                    p, q = v[e[0]], v[e[1]]
                    px, py = x0 + (p[a] - lo[a]) * sc, y0 + size - (p[b] - lo[b]) * sc
                    qx, qy = x0 + (q[a] - lo[a]) * sc, y0 + size - (q[b] - lo[b]) * sc
                    svg.append(f'<line x1="{px:.2f}" y1="{py:.2f}" x2="{qx:.2f}" y2="{qy:.2f}" stroke="{col}" stroke-width="0.8"/>')
    svg.append("</svg>")
    open(out, "w").write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
