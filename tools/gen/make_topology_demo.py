#!/usr/bin/env python3
"""Writes the topology-change demonstration (issue 30, item 2):
robots/topology_peg/scene.yaml (the paper's connectivity) and
robots/topology_peg/scene_corners.yaml (every coincident block corner tied,
the design space before issue 30), from one plate and one peg.

- Plate: an 8 × 8 × 1 cm box (OBJ written here) imported by
  `sdrs import --decomposer grid --max-hulls 16 --ties {shared-vertex|corners}`:
  4 × 4 × 1 blocks of 2 × 2 × 1 cm. Its root joint is made `fixed` at the
  world origin (the plate is held); its mass is a `given` 0.1 kg inertial
  (design-independent; a fixed link's mass does not enter the dynamics).
- Peg: a 6 × 6 mm square prism, 5 cm long, with a pyramid point 6 mm high,
  one convex hull, 50 g (lumped at its vertices), on a prismatic joint
  along z (it cannot tip over). Its point starts 2 mm above the plate's
  top at the plate centre, where four blocks meet, and falls under gravity.

Run from the repository root after `cargo build --release`:

    .venv/bin/python tools/gen/make_topology_demo.py

The outputs are committed; rerun only to regenerate them.
"""
import subprocess
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
SDRS = ROOT / "target" / "release" / "sdrs"
OUT = ROOT / "robots" / "topology_peg"

SIDE, THICK = 0.08, 0.01  # plate (m)
PEG_HALF, PEG_LEN, TIP = 0.003, 0.05, 0.006  # peg half-width, length, point height (m)
GAP = 0.002  # point above the plate's top (m)


def plate_obj(path):
    h, t = SIDE / 2, THICK / 2
    v = [(x, y, z) for z in (-t, t) for y in (-h, h) for x in (-h, h)]
    # Outward-oriented quads as triangles (vertex index = x + 2y + 4z).
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    lines = [f"v {x} {y} {z}" for x, y, z in v]
    for a, b, c, d in quads:
        lines += [f"f {a + 1} {b + 1} {c + 1}", f"f {a + 1} {c + 1} {d + 1}"]
    path.write_text("\n".join(lines) + "\n")


def peg_vertices():
    h = PEG_HALF
    square = [(sx * h, sy * h) for sx in (-1, 1) for sy in (-1, 1)]
    return ([[0.0, 0.0, 0.0]] + [[x, y, TIP] for x, y in square]
            + [[x, y, PEG_LEN] for x, y in square])


def scene(ties, tmp):
    obj = Path(tmp) / "plate.obj"
    plate_obj(obj)
    out = Path(tmp) / f"plate_{ties}.yaml"
    subprocess.run([str(SDRS), "import", str(obj), "--out", str(out), "--force", "-q",
                    "--decomposer", "grid", "--max-hulls", "16", "--ties", ties], check=True)
    s = yaml.safe_load(out.read_text())
    robot = s["robots"][0]
    robot["name"] = "plate"
    link = robot["links"][0]
    link["name"] = "plate"
    link["joint"] = {"name": "hold", "type": "fixed",
                     "origin": {"xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]}}
    link["mass_model"] = {"type": "given", "mass": 0.1, "com": [0.0, 0.0, 0.0],
                         "inertia": [5.4e-5, 0.0, 0.0, 5.4e-5, 0.0, 1.07e-4]}
    link.pop("surface_mesh", None)
    for t in robot["design"]["ties"]:
        for v in t:
            v["link"] = "plate"
    robot["design"].pop("attachments", None)
    robot["initial"] = {}
    robot["controller"] = {}
    peg = {
        "name": "peg",
        "base": {"xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]},
        "links": [{
            "name": "peg",
            "joint": {"name": "slide", "type": "prismatic", "axis": [0.0, 0.0, 1.0],
                      "origin": {"xyz": [0.0, 0.0, THICK / 2 + GAP], "rpy": [0.0, 0.0, 0.0]}},
            "mass": 0.05,
            "hulls": [{"vertices": peg_vertices()}],
        }],
    }
    return {
        "version": 1,
        "dt": 0.01,
        "steps": 40,
        # `extrapolate` pinned: the recorded outcome predates `quadratic` as the default.
        "solver": {"tol": 1.0e-9, "max_iters": 100, "predictor": "extrapolate"},
        "robots": [robot, peg],
        "contact": {"s": 0.0005, "mu": 0.0, "eps": 1.0e-6, "eps_force": 1.0e-6,
                    "exclude_adjacent": True},
    }


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for ties, name in (("shared-vertex", "scene.yaml"), ("corners", "scene_corners.yaml")):
            s = scene(ties, tmp)
            header = (
                "# Topology-change demonstration (issue 30): a plate of 4 × 4 grid blocks and a\n"
                "# peg that falls onto the point where four blocks meet (written by\n"
                f"# tools/gen/make_topology_demo.py). Plate ties: {ties.replace('-', '_')}"
                + (" (one auxiliary vertex per face-neighbour pair; corners free).\n"
                   if ties == "shared-vertex" else
                   " (coincident block corners are one variable).\n")
            )
            path = OUT / name
            path.write_text(header + yaml.safe_dump(s, sort_keys=False,
                                                    default_flow_style=None, width=200))
            print("wrote", path.relative_to(ROOT))


if __name__ == "__main__":
    main()
