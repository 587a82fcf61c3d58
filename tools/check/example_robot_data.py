#!/usr/bin/env python3
"""Import and simulate every URDF of example-robot-data (issue 32's 69-file sweep).

Usage: example_robot_data.py --sdrs BIN [--root DIR] [--out DIR] [--steps 100]

For each `*.urdf` under the package's `robots/` folder: `sdrs import F --out
OUT/N.yaml --force -q` (default options: base auto, ground for a floating
robot, PD hold) then `sdrs simulate OUT/N.yaml --steps STEPS -q --json`.
Per file: `ok`, `no-link` (the file has no <link>: not a robot), `import`
or `simulate` (the failing step, with the first line of its message), the
steps run and the wall time. A table on stdout, all rows in
OUT/summary.json; exit 1 when any file with a link fails.

The package is not in tools/setup/requirements.txt (its meshes are large
and CI does not run this sweep): install it by hand into the venv,
`.venv/bin/python -m pip install example-robot-data`, or pass `--root`
with a checkout's `robots/` folder. `package://` mesh paths resolve
through ROS_PACKAGE_PATH, set here to the folder above `robots/`.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time


def find_root(given):
    if given:
        return pathlib.Path(given)
    try:
        from example_robot_data.path import EXAMPLE_ROBOT_DATA_MODEL_DIR
        return pathlib.Path(EXAMPLE_ROBOT_DATA_MODEL_DIR)
    except ImportError:
        pass
    for p in pathlib.Path(sys.prefix).glob("share/example-robot-data/robots"):
        return p
    sys.exit("example-robot-data not found: .venv/bin/python -m pip install example-robot-data, or --root DIR")


def run(cmd, env):
    t = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    first = (p.stderr.strip().splitlines() or [""])[-1][:200]
    return p.returncode, first, time.time() - t


def one(sdrs, urdf, out, steps, env):
    name = "__".join(urdf.relative_to(urdf.parents[2]).with_suffix("").parts)
    row = {"file": str(urdf), "status": "ok", "steps": 0, "message": ""}
    if "<link" not in urdf.read_text(errors="replace"):
        row["status"] = "no-link"
        return row
    scene = out / f"{name}.yaml"
    code, msg, t_imp = run([sdrs, "import", str(urdf), "--out", str(scene), "--force", "-q"], env)
    row["import_s"] = round(t_imp, 2)
    if code != 0:
        row.update(status="import", message=msg)
        return row
    summary = out / f"{name}.summary.json"
    code, msg, t_sim = run([sdrs, "simulate", str(scene), "--steps", str(steps), "-q",
                            "--json", str(summary), "--out", str(out / f"{name}.csv")], env)
    row["simulate_s"] = round(t_sim, 2)
    if code != 0:
        row.update(status="simulate", message=msg)
        return row
    row["steps"] = json.loads(summary.read_text()).get("steps", 0)
    if row["steps"] != steps:
        row.update(status="simulate", message=f"{row['steps']} of {steps} steps")
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sdrs", required=True)
    ap.add_argument("--root")
    ap.add_argument("--out", default="out/example_robot_data")
    ap.add_argument("--steps", type=int, default=100)
    a = ap.parse_args()
    root = find_root(a.root)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["ROS_PACKAGE_PATH"] = os.pathsep.join(filter(None, [str(root.parent), env.get("ROS_PACKAGE_PATH")]))
    rows = [one(a.sdrs, u, out, a.steps, env) for u in sorted(root.rglob("*.urdf"))]
    for r in rows:
        print(f"{r['status']:9} {r['steps']:5} {r.get('import_s', 0):7.2f} {r.get('simulate_s', 0):7.2f}  "
              f"{pathlib.Path(r['file']).relative_to(root)}  {r['message']}")
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "no-link", "import", "simulate")}
    print(f"{len(rows)} files: {counts}")
    (out / "summary.json").write_text(json.dumps({"root": str(root), "counts": counts, "rows": rows}, indent=1))
    return 1 if counts["import"] + counts["simulate"] else 0


if __name__ == "__main__":
    sys.exit(main())
