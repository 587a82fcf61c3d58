#!/usr/bin/env python3
"""Top view of the topology demonstration's plate, before and after
co-design, for both connectivities: docs/topology_peg.png.

    .venv/bin/python tools/gen/picture_topology_demo.py OUT_SHARED OUT_CORNERS [PNG]

OUT_* are `sdrs optimize` output directories of robots/topology_peg/task.yaml
and task_corners.yaml (their scenes/scene.yaml hold the optimized design).
Panels (left to right): shared-vertex initial, shared-vertex optimized,
corner-tied initial, corner-tied optimized. Each block is the orthographic
projection of its hull onto the plate plane (grey; a white region inside
the plate is a vertical through-hole), the peg's 6 × 6 mm section red
outline at the centre, the plate's initial outline thin black. Rendered
with numpy (4× supersampled), written as PNG with zlib: no image library.
"""
import struct
import sys
import zlib
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
PX, SS, MARGIN = 260, 4, 0.012  # panel size (px), supersampling, margin (m)
HALF = 0.04 + MARGIN


def plate_hulls(scene_path):
    s = yaml.safe_load(Path(scene_path).read_text())
    link = next(r for r in s["robots"] if r["name"] == "plate")["links"][0]
    return [np.array(h["vertices"])[:, :2] for h in link["hulls"]]


def cross(o, a, b):
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def hull2d(p):
    """Counter-clockwise convex hull (monotone chain)."""
    pts = sorted(set(map(tuple, np.round(p, 12))))
    if len(pts) < 3:
        return np.array(pts)

    def half(points):
        out = []
        for q in points:
            while len(out) >= 2 and cross(out[-2], out[-1], q) <= 0:
                out.pop()
            out.append(q)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def fill(img, poly, color, grid):
    if len(poly) < 3:
        return
    inside = np.ones(grid[0].shape, bool)
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        inside &= (b[0] - a[0]) * (grid[1] - a[1]) - (b[1] - a[1]) * (grid[0] - a[0]) >= 0
    img[inside] = color


def outline(img, poly, color, grid, width):
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        d = b - a
        t = np.clip(((grid[0] - a[0]) * d[0] + (grid[1] - a[1]) * d[1]) / (d @ d), 0, 1)
        dist = np.hypot(grid[0] - a[0] - t * d[0], grid[1] - a[1] - t * d[1])
        img[dist <= width] = color


def render(polys, half, px, edge, marks):
    """A `px`-pixel square panel of the window `±half` (m): every 2-D point
    set of `polys` filled grey as its convex hull with an `edge`-wide
    outline, then each `(polygon, colour, width)` of `marks` outlined."""
    n = px * SS
    xs = np.linspace(-half, half, n)
    grid = (xs[None, :].repeat(n, 0), xs[::-1, None].repeat(n, 1))  # first axis right, second up
    img = np.full((n, n, 3), 255.0)
    hulls = [hull2d(p) for p in polys]
    for h in hulls:
        fill(img, h, (150, 150, 150), grid)
    for h in hulls:
        outline(img, h, (70, 70, 70), grid, edge)
    for poly, colour, width in marks:
        outline(img, poly, colour, grid, width)
    return img.reshape(px, SS, px, SS, 3).mean(axis=(1, 3))


def panel(hulls):
    sq = np.array([[-0.04, -0.04], [0.04, -0.04], [0.04, 0.04], [-0.04, 0.04]])
    peg = sq * (0.003 / 0.04)
    return render(hulls, HALF, PX, 0.00012, [(sq, (0, 0, 0), 0.00015), (peg, (220, 30, 30), 0.0003)])


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + row.astype(np.uint8).tobytes() for row in rgb)
    chunk = lambda tag, data: (struct.pack(">I", len(data)) + tag + data
                               + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    Path(path).write_bytes(png)


def main():
    shared, corners = Path(sys.argv[1]), Path(sys.argv[2])
    out = Path(sys.argv[3]) if len(sys.argv) > 3 else ROOT / "docs" / "topology_peg.png"
    demo = ROOT / "robots" / "topology_peg"
    panels = [
        plate_hulls(demo / "scene.yaml"),
        plate_hulls(shared / "scenes" / "scene.yaml"),
        plate_hulls(demo / "scene_corners.yaml"),
        plate_hulls(corners / "scenes" / "scene_corners.yaml"),
    ]
    gap = np.full((PX, 8, 3), 255.0)
    row = []
    for k, hs in enumerate(panels):
        row.append(panel(hs))
        if k < 3:
            row.append(gap if k != 1 else np.zeros((PX, 3, 3)))
    write_png(out, np.concatenate(row, axis=1))
    print("wrote", out)


if __name__ == "__main__":
    main()
