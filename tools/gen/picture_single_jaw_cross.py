#!/usr/bin/env python3
"""The single jaw's right leg seen along the cross's arm (issue 30, the
standing cross): docs/single_jaw_cross.png.

    .venv/bin/python tools/gen/picture_single_jaw_cross.py [SCENE ...] [--out PNG]

Each SCENE (default: robots/single_jaw_cross/scene.yaml and scene_hole.yaml;
an `sdrs optimize` output's scenes/scene.yaml works too) is one panel: every
block of the jaw's right leg (jaw frame x ≥ 0.10 m) projected along x onto
the y–z plane (grey; a white region inside the leg is a through-hole along
the arm), the rod's 6 × 6 mm section at the arm's axis red, a 60 × 60 mm
window around it. Rendered as tools/gen/picture_topology_demo.py does.

`--rod SCENE=DY,DZ` (mm, repeatable) draws that panel's rod section at an
offset from the aim instead: where an optimized path takes the arm (the
nineteenth session's co-design threads it through a hole it drilled
−15…−33 mm, +15…+27 mm from the aim; notes/paper-step-rule.md).
"""
import sys
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
from picture_topology_demo import ROOT, render, write_png  # noqa: E402
from make_grasp_scenes import CROSS_ROD, SJ_GRID_Y, SJ_GRID_Z  # noqa: E402

PX, HALF = 260, 0.03  # panel size (px), half window (m)


def leg_sections(scene_path):
    s = yaml.safe_load(Path(scene_path).read_text())
    link = next(r for r in s["robots"] if r["name"] == "gripper")["links"][0]
    centre = np.array([SJ_GRID_Y, SJ_GRID_Z])
    out = []
    for h in link["hulls"]:
        v = np.array(h["vertices"])
        if v[:, 0].min() >= 0.10:
            out.append(v[:, 1:] - centre)
    return out


def panel(sections, offset=(0.0, 0.0)):
    r = CROSS_ROD / 2
    rod = np.array([[-r, -r], [r, -r], [r, r], [-r, r]]) + np.array(offset)
    return render(sections, HALF, PX, 0.00008, [(rod, (220, 30, 30), 0.0002)])


def main():
    args = sys.argv[1:]
    out = ROOT / "docs" / "single_jaw_cross.png"
    if "--out" in args:
        k = args.index("--out")
        out = Path(args[k + 1])
        del args[k:k + 2]
    offsets = {}
    while "--rod" in args:
        k = args.index("--rod")
        scene, dydz = args[k + 1].split("=")
        offsets[scene] = tuple(float(v) / 1000 for v in dydz.split(","))
        del args[k:k + 2]
    task = ROOT / "robots" / "single_jaw_cross"
    scenes = args or [task / "scene.yaml", task / "scene_hole.yaml"]
    gap = np.full((PX, 8, 3), 255.0)
    row = []
    for k, sc in enumerate(scenes):
        row.append(panel(leg_sections(sc), offsets.get(str(sc), (0.0, 0.0))))
        if k + 1 < len(scenes):
            row.append(gap)
    write_png(out, np.concatenate(row, axis=1))
    print("wrote", out)


if __name__ == "__main__":
    main()
