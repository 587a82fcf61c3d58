#!/usr/bin/env python3
"""Writes the grasping benchmarks' scenes (robots/<gripper>/scene_*.yaml).

Each scene = the gripper imported by `sdrs import --decomposer grid` (the
paper's block design space; the three-fingered hand: `--decomposer vhacd
--max-hulls 4`, the paper's 4 V-HACD hulls per link) + one object (imported
OBJ, V-HACD hulls) on a ground plane, with the prescribed base path and the
closed-pose targets of the task header. Run from the repository root after `cargo build --release`:

    .venv/bin/python tools/gen/make_grasp_scenes.py [--blocks 156] [--which parallel_jaw,parallel_jaw_stand,single_jaw,single_jaw_cross,three_finger]

The outputs are committed; rerun only to regenerate them.
"""
import argparse
import random
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
SDRS = ROOT / "target" / "release" / "sdrs"


# Every scene pins `predictor: extrapolate` (2θ^t − θ^{t−1}): the outcomes
# recorded in docs/paper-benchmarks.md were measured with it, before
# `quadratic` became the solver's default (2026-11-29, seventh session). The
# predictor changes only the cost of a step, but these tasks are chaotic:
# re-measure them before unpinning.
def sdrs_import(src, out, *args):
    subprocess.run([str(SDRS), "import", str(src), "--out", str(out), "--force", "-q", *args],
                   check=True)
    return yaml.safe_load(Path(out).read_text())


def object_hulls(obj, tmp, convex):
    dec = ["--decomposer", "hull"] if convex else ["--decomposer", "vhacd", "--max-hulls", "6"]
    s = sdrs_import(obj, Path(tmp) / (obj.stem + ".yaml"), *dec)
    return [{"vertices": h["vertices"]} for h in s["robots"][0]["links"][0]["hulls"]]


def write(path, scene, header):
    text = header + yaml.safe_dump(scene, sort_keys=False, default_flow_style=None, width=200)
    path.write_text(text)
    print("wrote", path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)


def jaw_scenes(blocks, tmp, out_dir, lift0, bottom, header, obstacles=(), digits=None):
    """The four parallel-jaw scenes (cube, cylinder, ball, plus) in `out_dir`:
    the gripper imported as 140 blocks per jaw, the palm starting at lift
    `lift0` (relative to the URDF pose), each object's lowest point at
    `bottom` (m), the static `obstacles`, each file's comment `header(name,
    rise)`; `digits` rounds the lift target and the object's height."""
    first = ROOT / "robots" / "parallel_jaw_gripper"
    g = sdrs_import(first / "parallel_jaw_gripper.urdf", Path(tmp) / "pj.yaml", "--decomposer", "grid",
                    "--max-hulls", str(blocks), "--designable", "jaw_left,jaw_right")
    robot = g["robots"][0]
    robot["name"] = "gripper"
    g["contact"]["exclude"] = [[a.replace("parallel_jaw_gripper/", "gripper/") for a in pair]
                               for pair in g["contact"]["exclude"]]
    rnd = (lambda x: x) if digits is None else (lambda x: round(x, digits))
    rng = random.Random(12)  # the paper's "random target position", drawn once
    for name, convex in [("cube", True), ("cylinder", True), ("ball", True), ("plus", False)]:
        rise = round(rng.uniform(0.10, 0.20), 3)
        hulls = object_hulls(first / "objects" / f"{name}.obj", tmp, convex)
        zmin = min(v[2] for h in hulls for v in h["vertices"])
        r = dict(robot)
        r["controller"] = {
            "kp": 0.3, "kd": 0.003,
            "gains": {"lift": {"kp": 3000.0, "kd": 30.0}},
            "targets": {
                "lift": {"type": "table", "times": [0.0, 0.6, 1.4], "values": [lift0, lift0, rnd(lift0 + rise)]},
                # closed pose θ⋆: each jaw turned 0.3 rad inwards about y.
                "jaw_left_pivot_x+jaw_left_pivot_y": [{"type": "constant", "value": 0.0},
                                                      {"type": "constant", "value": -0.3}],
                "jaw_right_pivot_x+jaw_right_pivot_y": [{"type": "constant", "value": 0.0},
                                                        {"type": "constant", "value": 0.3}],
            },
        }
        r["initial"] = {"lift": {"q": [lift0]}}
        scene = {
            "version": 1, "dt": 0.01, "steps": 180,
            "solver": {"tol": 1e-6, "max_iters": 100, "predictor": "extrapolate"},
            "robots": [r],
            "objects": [{"name": name, "mass": 0.05, "hulls": hulls,
                         "initial": {"q": [0.0, 0.0, rnd(bottom - zmin), 0.0, 0.0, 0.0]}}],
        }
        if obstacles:
            scene["obstacles"] = list(obstacles)
        scene["ground"] = {"height": 0.0}
        scene["contact"] = {**g["contact"], "s": 0.003, "mu": 0.05}
        write(out_dir / f"scene_{name}.yaml", scene, header(name, rise))


def parallel_jaw(blocks, tmp):
    # Lift: the palm starts 0.215 m below the URDF pose (jaw feet beside the
    # object's centre), holds while the jaws close, then rises by `rise`;
    # the objects on the ground (1 mm clearance).
    jaw_scenes(blocks, tmp, ROOT / "robots" / "parallel_jaw_gripper", -0.215, 0.001,
               lambda name, rise:
               f"# Parallel-jaw gripper grasping the {name} (written by tools/gen/make_grasp_scenes.py;\n"
               f"# see task.yaml for the settings). Lift rise {rise} m.\n")


# Parallel jaw, second task (robots/parallel_jaw_stand/task.yaml;
# notes/grasping-parallel-jaw-stand.md): each object on a static post so that
# a jaw point can get below it, the jaws' feet starting STAND_C above the
# object's lowest point (the first task: 0.025, feet 2.5 cm above the ground).
STAND_TOP = 0.06        # post top above the ground (m)
STAND_HALF = 0.010      # post half-width in x and y (m)
STAND_C = 0.005         # jaw feet's bottom above the object's lowest point (m), by the plan's rule
JAW_FOOT_BELOW_PALM = 0.16   # the jaw mesh's lowest point below the palm frame (m)
PALM_URDF_Z = 0.4            # the palm frame's height at lift = 0 (m)


def parallel_jaw_stand(blocks, tmp, c, out_dir):
    bottom = STAND_TOP + 0.001  # every object's lowest point (1 mm above the post)
    lift0 = round(bottom + c + JAW_FOOT_BELOW_PALM - PALM_URDF_Z, 6)
    h = STAND_HALF
    post = {"name": "stand", "hulls": [{"vertices": [[x, y, z] for x in (-h, h) for y in (-h, h)
                                                     for z in (0.0, STAND_TOP)]}]}
    jaw_scenes(blocks, tmp, out_dir, lift0, bottom,
               lambda name, rise:
               f"# Parallel-jaw gripper, the {name} on a stand (written by tools/gen/make_grasp_scenes.py\n"
               f"# --which parallel_jaw_stand; see task.yaml). Jaw feet {c} m above the object's lowest\n"
               f"# point; lift rise {rise} m.\n",
               obstacles=[post], digits=6)


# Single-jaw path (task.yaml header): four stages of 1.2 s (H = 480, dt = 0.01):
# knots at the stage boundaries, coordinates of the free root relative to
# the URDF pose (palm 0.4 m up). x, y, z (m), then the rotation vector (rad).
SJ_TIMES = [0.0, 1.2, 2.4, 3.6, 4.8]
SJ_PATH = {
    "x": [0.0, 0.0, 0.04, 0.04, 0.04],      # approach: the left leg meets the X
    "y": [0.0, 0.0, 0.0, 0.0, 0.0],
    "z": [0.0, -0.262, -0.262, -0.262, -0.062],  # lower (leg tips 18 mm up), lift 0.2 m
    "rx": [0.0, 0.0, 0.0, 0.0, 0.0],
    "ry": [0.0, 0.0, 0.0, 0.0, 0.0],
    "rz": [0.0, 0.0, 0.3, 0.0, 0.0],        # turn while grasping, re-orient
}


def single_jaw(blocks, tmp):
    d = ROOT / "robots" / "single_jaw_gripper"
    g = sdrs_import(d / "single_jaw_gripper.urdf", Path(tmp) / "sj.yaml", "--decomposer", "grid",
                    "--max-hulls", str(blocks), "--designable", "jaw")
    robot = g["robots"][0]
    robot["name"] = "gripper"
    hulls = object_hulls(d / "objects" / "x_object.obj", tmp, False)
    zmin = min(v[2] for h in hulls for v in h["vertices"])
    robot["controller"] = {
        "kp": 0.0, "kd": 0.0,
        "gains": {"base": {"kp": 3000.0, "kd": 3.0}},
        "targets": {"base": [{"type": "table", "times": list(SJ_TIMES), "values": list(SJ_PATH[k])}
                             for k in ["x", "y", "z", "rx", "ry", "rz"]]},
    }
    scene = {
        "version": 1, "dt": 0.01, "steps": 480,
        "solver": {"tol": 1e-6, "max_iters": 100, "predictor": "extrapolate"},
        "robots": [robot],
        "objects": [{"name": "x_object", "mass": 0.05, "hulls": hulls,
                     "initial": {"q": [0.0, 0.0, -zmin + 0.001, 0.0, 0.0, 0.0]}}],
        "ground": {"height": 0.0},
        "contact": {**g["contact"], "s": 0.003, "mu": 0.05},
    }
    write(d / "scene.yaml", scene,
          "# Single-jaw gripper and the X-shaped object (written by tools/gen/make_grasp_scenes.py;\n"
          "# see task.yaml for the settings and the prescribed base path).\n")


# Single jaw, second task (issue 30, robots/single_jaw_cross/task.yaml, whose
# header records every setting and each change with the outcome that led to
# it): a cross of 6 mm rods ("X" turned 45° in its plane so that one arm is
# horizontal) standing on a foot, its left arm pointed and aimed at a line
# where four blocks of the jaw's right leg meet. The jaw starts left of the
# cross, is lowered, and moves +x until its right leg's outer face is at
# x = −0.013 m (10 mm from the upright): the arm must cross the leg's full
# thickness (a through-hole), then the jaw holds and lifts 0.2 m.
CROSS_ROD = 0.006       # rod section (m), square (first runs: 0.012)
CROSS_ARM = 0.07        # horizontal arm half-length to the tip's base (m)
CROSS_TIP = 0.012       # pointed tip length (m)
CROSS_Z = 0.08          # horizontal arm's axis height (m)
CROSS_TOP = 0.14        # top of the upright (m)
CROSS_FOOT = (0.04, 0.01)  # foot side, thickness (m)
SJ_GRID_Z = -0.12 + 2 * 0.17 / 7   # jaw-frame z of the leg's grid line (rows 2|3 from the tip)
SJ_GRID_Y = 0.012                  # jaw-frame y of the leg's grid line (columns 3|4)
SJ2_TIMES = [0.0, 1.2, 2.4, 3.6, 4.8]
SJ2_X0, SJ2_X1 = -0.25, -0.163     # jaw x at the start and after the approach (m)
# Jaw height, relative to the URDF pose (origin 0.4 m up), that puts the
# leg's grid line at the arm's axis: the cross rests 2 mm above the ground
# (the barrier's equilibrium at s = 1 mm) and the jaw sags 1.6 mm below its
# target (PD against gravity), both measured with `sdrs simulate` (the first
# runs ignored both and aimed 7.6 mm too low).
SJ2_S = 0.001  # barrier support (m); first runs: 0.003
SJ2_REST, SJ2_SAG = 0.002, 0.0016
SJ2_Z = round(CROSS_Z + SJ2_REST - SJ_GRID_Z - 0.4 + SJ2_SAG, 6)
SJ2_PATH = {
    "x": [SJ2_X0, SJ2_X0, SJ2_X1, SJ2_X1, SJ2_X1],   # approach in stage 2
    "y": [-SJ_GRID_Y] * 5,
    "z": [0.0, SJ2_Z, SJ2_Z, SJ2_Z, SJ2_Z + 0.2],   # lower in stage 1, lift in stage 4
    "rx": [0.0] * 5, "ry": [0.0] * 5, "rz": [0.0] * 5,
}


def box(x0, x1, y0, y1, z0, z1):
    return {"vertices": [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]}


def cross_hulls():
    """The cross's convex pieces (object frame: foot on z = 0, upright on the z axis)."""
    r, a, t, zc = CROSS_ROD / 2, CROSS_ARM, CROSS_TIP, CROSS_Z
    f, ft = CROSS_FOOT[0] / 2, CROSS_FOOT[1]
    hulls = [box(-f, f, -f, f, 0.0, ft), box(-r, r, -r, r, ft, zc - r),
             box(-a, a, -r, r, zc - r, zc + r), box(-r, r, -r, r, zc + r, CROSS_TOP)]
    for s in (-1.0, 1.0):
        base = [[s * a, y, z] for y in (-r, r) for z in (zc - r, zc + r)]
        hulls.append({"vertices": base + [[s * (a + t), 0.0, zc]]})
    return hulls


def single_jaw_cross(blocks, tmp, out_dir):
    d = ROOT / "robots" / "single_jaw_gripper"
    g = sdrs_import(d / "single_jaw_gripper.urdf", Path(tmp) / "sj.yaml", "--decomposer", "grid",
                    "--max-hulls", str(blocks), "--designable", "jaw")
    robot = g["robots"][0]
    robot["name"] = "gripper"
    robot["controller"] = {
        "kp": 0.0, "kd": 0.0,
        "gains": {"base": {"kp": 3000.0, "kd": 3.0}},
        "targets": {"base": [{"type": "table", "times": list(SJ2_TIMES), "values": [round(v, 6) for v in SJ2_PATH[k]]}
                             for k in ["x", "y", "z", "rx", "ry", "rz"]]},
    }
    robot["initial"] = {"base": {"q": [SJ2_X0, -SJ_GRID_Y, 0.0, 0.0, 0.0, 0.0]}}
    # The URDF pose (jaw origin 0.4 m up) is the path's reference: undo the
    # importer's drop onto the ground.
    robot["base"] = {"xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]}
    scene = {
        "version": 1, "dt": 0.01, "steps": 480,
        "solver": {"tol": 1e-6, "max_iters": 100, "predictor": "extrapolate"},
        "robots": [robot],
        "objects": [{"name": "x_object", "mass": 0.05, "hulls": cross_hulls(),
                     "initial": {"q": [0.0, 0.0, 0.001, 0.0, 0.0, 0.0]}}],
        "ground": {"height": 0.0},
        # s = 1 mm: the barrier acts within ≈ 2s of a surface, and a 6 mm rod
        # in a hole the bound can open (≈ ±10 mm) needs less than s = 3 mm's 6 mm.
        "contact": {**g["contact"], "s": SJ2_S, "mu": 0.05},
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    write(out_dir / "scene.yaml", scene,
          "# Single-jaw gripper and the standing cross (written by tools/gen/make_grasp_scenes.py\n"
          "# --which single_jaw_cross; see task.yaml for the settings and the prescribed base path).\n")
    drill(robot["links"][0]["hulls"], SJ_HOLE_HALF, SJ_HOLE_FRACTION)
    write(out_dir / "scene_hole.yaml", scene,
          "# scene.yaml with a hand-made through-hole in the jaw's right leg along the cross's arm\n"
          f"# (tools/gen/make_grasp_scenes.py `drill`: every leg vertex within {SJ_HOLE_HALF} m (max-norm, in y-z)\n"
          f"# of the arm's axis moved {SJ_HOLE_FRACTION:.0%} of the way out to that square). A design within\n"
          "# the task's bound that lifts the cross: tests/grasping.rs.\n")


# The hand-made hole of scene_hole.yaml (single_jaw_cross): found by
# interpolating between the initial jaw and a 12 mm square hole (fraction
# 1), which lets the arm through but not hang; from 38 % to 48 % the arm
# jams in the hole and the cross is carried (notes/grasping-topology-change.md §8).
SJ_HOLE_HALF, SJ_HOLE_FRACTION = 0.012, 0.4


def drill(hulls, half, fraction):
    """Moves every right-leg vertex (jaw frame x in [0.10, 0.16]) that lies
    within `half` (max-norm in y-z) of the arm's axis `fraction` of the way
    out to the square of half-width `half`; a vertex on the axis moves
    diagonally towards its own block's centre."""
    cy, cz = SJ_GRID_Y, SJ_GRID_Z
    for h in hulls:
        vs = h["vertices"]
        my = sum(v[1] for v in vs) / len(vs)
        mz = sum(v[2] for v in vs) / len(vs)
        for v in vs:
            if not 0.10 <= v[0] <= 0.16:
                continue
            dy, dz = v[1] - cy, v[2] - cz
            n = max(abs(dy), abs(dz))
            if n >= half:
                continue
            if n < 1e-6:  # on the axis: towards the block's own centre
                dy, dz = (1.0 if my > cy else -1.0), (1.0 if mz > cz else -1.0)
                n = 1.0
            k = half / n
            v[1] += fraction * (cy + dy * k - v[1])
            v[2] += fraction * (cz + dz * k - v[2])


# Three-fingered hand (task.yaml header): the URDF's six finger links are
# carried by an added palm on a free root joint (the prescribed base path);
# the palm frame's origin is the grasp point, HAND_Z above the ground.
HAND_Z = 0.05           # palm origin (grasp point) height at the start (m)
HAND_JOINTS_Z = 0.085    # finger base joints above the palm origin (m)
HAND_OPEN, HAND_CLOSED = 0.75, -0.1  # finger base angles (rad) initial / θ⋆; mid joints 0
HAND_TIMES = [0.0, 0.6, 1.4, 2.0]    # hold while closing, move, hold (s)


def random_target(rng):
    """The paper's "target position located in any orientation", drawn once per
    object: rise U(0.10, 0.20) m, horizontal offset U(−0.05, 0.05) m per axis,
    rotation by U(0, 0.4) rad about a uniformly random axis."""
    import math
    dx, dy = (round(rng.uniform(-0.05, 0.05), 3) for _ in range(2))
    dz = round(rng.uniform(0.10, 0.20), 3)
    u, ph = rng.uniform(-1.0, 1.0), rng.uniform(0.0, 2.0 * math.pi)
    axis = [math.sqrt(1 - u * u) * math.cos(ph), math.sqrt(1 - u * u) * math.sin(ph), u]
    ang = rng.uniform(0.0, 0.4)
    return [dx, dy, dz], [round(ang * a, 4) for a in axis]


def three_finger(tmp):
    d = ROOT / "robots" / "three_finger_hand"
    g = sdrs_import(d / "three_finger_hand.urdf", Path(tmp) / "hand.yaml", "--decomposer", "vhacd",
                    "--max-hulls", "4")
    robot = g["robots"][0]
    robot["name"] = "hand"
    for link in robot["links"]:
        if link["parent"] is None:  # a finger base on the URDF's world: now on the palm
            link["parent"] = "palm"
            o = link["joint"]["origin"]["xyz"]
            link["joint"]["origin"]["xyz"] = [o[0], o[1], HAND_JOINTS_Z]
    fingers = [l["name"] for l in robot["links"]]
    palm = {
        "name": "palm", "parent": None,
        "joint": {"name": "base", "type": "free",
                  "origin": {"xyz": [0.0, 0.0, HAND_Z], "rpy": [0.0, 0.0, 0.0]}},
        "mass_model": {"type": "given", "mass": 0.5, "com": [0.0, 0.0, HAND_JOINTS_Z + 0.04],
                       "inertia": [0.001, 0.0, 0.0, 0.001, 0.0, 0.001]},
        # a plate above the finger joints (clear of the proximal links' swing)
        "hulls": [{"box": {"size": [0.14, 0.14, 0.02], "center": [0.0, 0.0, HAND_JOINTS_Z + 0.04]}}],
    }
    robot["links"] = [palm] + robot["links"]
    design = robot["design"]
    design["designable"] = fingers
    exclude = [[a.replace("three_finger_hand/", "hand/") for a in pair] for pair in g["contact"]["exclude"]]
    exclude += [["hand/palm", f"hand/{f}"] for f in fingers]
    rng = random.Random(12)
    for name in ["cube", "cylinder", "ball"]:
        hulls = object_hulls(d / "objects" / f"{name}.obj", tmp, True)
        zmin = min(v[2] for h in hulls for v in h["vertices"])
        zc = -zmin + 0.001  # the object's centre on the ground (1 mm clearance)
        pos, rot = random_target(rng)
        r = dict(robot)
        finger_targets = {}
        for f in fingers:
            j = next(l["joint"]["name"] for l in robot["links"] if l["name"] == f)
            if j.endswith("_base"):  # the closed pose θ⋆ as the target throughout (paper)
                finger_targets[j] = {"type": "constant", "value": HAND_CLOSED}
            else:
                finger_targets[j] = {"type": "constant", "value": 0.0}
        # position in the attachment frame (relative to the start), rotation vector
        base = [{"type": "table", "times": list(HAND_TIMES), "values": [0.0, 0.0, pos[i], pos[i]]}
                for i in range(3)]
        base += [{"type": "table", "times": list(HAND_TIMES), "values": [0.0, 0.0, rot[i], rot[i]]}
                 for i in range(3)]
        r["controller"] = {
            "kp": 300.0, "kd": 3.0,
            "gains": {"base": {"kp": 3000.0, "kd": 30.0}},
            "targets": {"base": base, **finger_targets},
        }
        r["initial"] = {j: {"q": [HAND_OPEN]} for j in finger_targets if j.endswith("_base")}
        scene = {
            "version": 1, "dt": 0.01, "steps": 200,
            "solver": {"tol": 1e-6, "max_iters": 100, "predictor": "extrapolate"},
            "robots": [r],
            "objects": [{"name": name, "mass": 0.05, "hulls": hulls,
                         "initial": {"q": [0.0, 0.0, zc, 0.0, 0.0, 0.0]}}],
            "ground": {"height": 0.0},
            # ipc.dhat: IPC only (the mesh baseline, `--contact ipc`), ignored by SDRS: d̂ = 3 mm =
            # the SDRS barrier support s. Set 2026-11-26 after measuring that IPC's default
            # d̂ = 1 mm (and 1 mm with κ = 1e4 or 1e6) stops at step 60 of the cube trajectory
            # (line search: no decrease at ‖∇O‖∞ = 1.4e-3); with 3 mm all three run 200 steps.
            "contact": {**g["contact"], "exclude": exclude, "s": 0.003, "mu": 0.05, "ipc": {"dhat": 0.003}},
        }
        write(d / f"scene_{name}.yaml", scene,
              f"# Three-fingered hand grasping the {name} (written by tools/gen/make_grasp_scenes.py;\n"
              f"# see task.yaml for the settings). Object centre {zc:.4f} m; target offset {pos} m,\n"
              f"# rotation vector {rot} rad.\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--blocks", type=int, default=156)
    ap.add_argument("--which", default="parallel_jaw")
    ap.add_argument("--out-dir", type=Path, default=None,
                    help="single_jaw_cross / parallel_jaw_stand: where to write the scenes (default robots/<task>)")
    ap.add_argument("--stand-c", type=float, default=STAND_C,
                    help="parallel_jaw_stand: jaw feet's bottom above the object's lowest point (m)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        which = a.which.split(",")
        if "parallel_jaw" in which:
            parallel_jaw(a.blocks, tmp)
        if "parallel_jaw_stand" in which:
            parallel_jaw_stand(a.blocks, tmp, a.stand_c,
                               a.out_dir or ROOT / "robots" / "parallel_jaw_stand")
        if "single_jaw_cross" in which:
            single_jaw_cross(a.blocks, tmp, a.out_dir or ROOT / "robots" / "single_jaw_cross")
        if "single_jaw" in which:
            single_jaw(a.blocks, tmp)
        if "three_finger" in which:
            three_finger(tmp)


if __name__ == "__main__":
    sys.exit(main())
