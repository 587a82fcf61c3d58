#!/usr/bin/env python3
"""Free swing of an SDRS robot against MuJoCo: joint-angle error vs Δt.

    python tools/check/swing_vs_mujoco.py SCENE.yaml --sdrs target/release/sdrs \
        [--q "0.05 0.1 ..."] [--gravity 0 0 9.81] [--duration 1.0] \
        [--dts 1e-2,3e-3,1e-3,3e-4,1e-4] [--mj-timestep 2e-5] [--work DIR] [--json out.json]

SCENE is a one-robot scene with revolute/prismatic joints (e.g. written by
`sdrs import`). The swing scene drops the controller, contact, ground and
joint limits (MuJoCo gets none either), sets the initial coordinates
`--q` (one per joint, in scene order; default all zero) and `--gravity`, and
is simulated by `sdrs simulate` at each Δt and by MuJoCo's RK4 at
`--mj-timestep` (through tools/check/mujoco_from_export.py, which gives MuJoCo
the same kinematics and each link's mass, COM and inertia from its
`mass_model`). Printed: per Δt the largest joint-angle difference over
`--duration` (sampled every 0.01 s) and the observed order
log(e₁/e₂)/log(Δt₁/Δt₂) between consecutive Δt; SDRS's implicit scheme is
first order, so the order should approach 1. Exit 2 on bad input.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    import yaml
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e.name}", file=sys.stderr)
    sys.exit(3)

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(f"command failed: {' '.join(cmd)}\n{r.stderr}", file=sys.stderr)
        sys.exit(1)


def max_error(sdrs_csv, mj_csv):
    a = np.genfromtxt(sdrs_csv, delimiter=",", names=True)
    b = np.genfromtxt(mj_csv, delimiter=",", names=True)
    t = b["t"]
    joints = [n for n in b.dtype.names if n != "t"]
    return max(float(np.abs(np.interp(t, a["t"], a[j]) - b[j]).max()) for j in joints)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--sdrs", default=os.path.join(HERE, "..", "..", "target", "release", "sdrs"))
    ap.add_argument("--q", default=None, help="initial coordinates, space separated, scene joint order")
    ap.add_argument("--gravity", type=float, nargs=3, default=[0.0, 0.0, -9.81])
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--dts", default="1e-2,3e-3,1e-3,3e-4,1e-4")
    ap.add_argument("--mj-timestep", type=float, default=2e-5)
    ap.add_argument("--work", default=None)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    with open(a.scene) as f:
        scene = yaml.safe_load(f)
    if len(scene.get("robots", [])) != 1:
        print("the scene must have exactly one robot", file=sys.stderr)
        return 2
    robot = scene["robots"][0]
    joints = [l["joint"].get("name", l["name"]) for l in robot["links"]
              if l["joint"]["type"] in ("revolute", "prismatic")]
    q = [0.0] * len(joints) if a.q is None else [float(v) for v in a.q.split()]
    if len(q) != len(joints):
        print(f"--q needs {len(joints)} values ({', '.join(joints)}), got {len(q)}", file=sys.stderr)
        return 2
    for k in ("contact", "ground", "obstacles", "objects", "effects"):
        scene.pop(k, None)
    scene["gravity"] = list(a.gravity)
    robot["controller"] = {}
    robot.pop("design", None)
    robot["initial"] = {j: {"q": [v]} for j, v in zip(joints, q)}
    for l in robot["links"]:
        l["joint"].pop("limit", None)
        l["joint"].pop("mimic", None)
    work = a.work or tempfile.mkdtemp(prefix="sdrs-swing-")
    os.makedirs(work, exist_ok=True)
    base = os.path.join(work, "swing.yaml")
    scene["dt"], scene["steps"] = 1e-3, 1
    with open(base, "w") as f:
        yaml.safe_dump(scene, f)
    export = os.path.join(work, "export")
    run([a.sdrs, "simulate", base, "-q", "--export", export, "--out", os.path.join(work, "x.csv")])
    mj = os.path.join(work, "mujoco.csv")
    run([sys.executable, os.path.join(HERE, "mujoco_from_export.py"), base, export, "--out", mj,
         "--duration", str(a.duration), "--noise", "0", "--period", "0.01",
         "--timestep", str(a.mj_timestep), "--integrator", "RK4"])
    rows = []
    for dt in [float(v) for v in a.dts.split(",")]:
        scene["dt"], scene["steps"] = dt, int(round(a.duration / dt))
        path = os.path.join(work, f"swing_{dt:g}.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(scene, f)
        out = os.path.join(work, f"sdrs_{dt:g}.csv")
        run([a.sdrs, "simulate", path, "-q", "--out", out])
        rows.append({"dt": dt, "max_error_rad": max_error(out, mj)})
    print(f"{'dt (s)':>10} {'max |Δθ| (rad)':>16} {'order':>7}")
    for i, r in enumerate(rows):
        if i > 0:
            p = rows[i - 1]
            r["order"] = math.log(p["max_error_rad"] / r["max_error_rad"]) / math.log(p["dt"] / r["dt"])
        order = f"{r['order']:7.2f}" if "order" in r else " " * 7
        print(f"{r['dt']:>10.0e} {r['max_error_rad']:>16.3e} {order}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"scene": a.scene, "q": q, "gravity": a.gravity, "duration": a.duration,
                       "mujoco": {"integrator": "RK4", "timestep": a.mj_timestep}, "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
