"""A copy of a scene with some links' hulls scaled along one axis of their
link frame, about the frame's origin (e.g. a biped's feet shortened about
the ankle): every hull vertex's coordinate on AXIS times K. Nothing else of
the scene changes (masses, joints, controller, design sections); relative
paths in the copy are not rewritten, so write it next to the original.

    python tools/gen/scale_link_hulls.py SCENE.yaml OUT.yaml --links biped/left_foot,biped/right_foot --axis x --k 0.65

Refuses to overwrite OUT, an unknown link, an axis other than x/y/z and
a K outside (0, 10].
"""
import argparse
import sys
from pathlib import Path

import yaml


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--links", required=True, help="robot/link,robot/link,…")
    ap.add_argument("--axis", required=True)
    ap.add_argument("--k", type=float, required=True)
    a = ap.parse_args()
    out = Path(a.out)
    if out.exists():
        sys.exit(f"{out}: exists, not overwritten")
    if a.axis not in ("x", "y", "z"):
        sys.exit(f"--axis: x, y or z, got {a.axis!r}")
    if not (0.0 < a.k <= 10.0):
        sys.exit(f"--k: in (0, 10], got {a.k}")
    ax = "xyz".index(a.axis)
    scene = yaml.safe_load(Path(a.scene).read_text())
    for name in a.links.split(","):
        robot, link = name.split("/")
        r = next((r for r in scene["robots"] if r["name"] == robot), None)
        l = next((l for l in (r or {}).get("links", []) if l["name"] == link), None)
        if l is None:
            sys.exit(f"{a.scene}: no link {name}")
        for h in l["hulls"]:
            for v in h["vertices"]:
                v[ax] = v[ax] * a.k
    head = f"# {a.scene} with the hulls of {a.links} scaled by {a.k} along {a.axis} (tools/gen/scale_link_hulls.py)\n"
    out.write_text(head + yaml.safe_dump(scene, sort_keys=False))
    print(f"{out}: written")


if __name__ == "__main__":
    main()
