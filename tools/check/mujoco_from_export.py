"""Independent-engine data for `sdrs calibrate`: convert an SDRS robot to MJCF
and simulate it with MuJoCo, optionally with one effect switched on.

    python tools/check/mujoco_from_export.py SCENE.yaml EXPORT_DIR --out data.csv \
        [--damping C] [--frictionloss F] [--armature A] [--gain G] \
        [--duration 1.2] [--period 0.01] [--noise 1e-4] [--seed 1] [--timestep 1e-4] \
        [--integrator implicitfast|implicit|RK4|Euler] [--mjcf model.xml] [--model calibrated.xml]

EXPORT_DIR is written by `sdrs simulate SCENE.yaml --export EXPORT_DIR`: the
hull vertices of every link come from its `hulls.json`, and `poses.csv`
(step 0) checks the converted kinematics (link poses at θ^0 must agree to
1e-9 m). Masses follow the link's `mass_model`: the SDRS lumped vertex
masses by default (a link's `mass` divided equally over its hull vertices,
or `vertex_mass` per vertex), a `given` inertial, or `solid` hulls (trimesh's
polyhedral integrals, hulls superposed); each MuJoCo body gets the exact
mass, centre of mass and inertia tensor, so both engines integrate the same
rigid bodies.

The controller is the scene's stable-PD in SDRS's convention, applied as a
joint torque each MuJoCo step: τ = 2k_p(θ* − θ) + (2k_d/Δt_sdrs)(θ̇* − θ̇)
(θ*, θ̇* from the scene's sine/constant targets). Effects, on every joint:
`--damping` (MuJoCo joint damping, N·m·s/rad), `--frictionloss` (dry
friction, N·m), `--armature` (kg·m²), `--gain` (the PD torque × G).

With `--sdrs BIN`, the MJCF comes from `BIN export-mjcf SCENE` (the toolkit's
own writer, src/output/mjcf.rs: same kinematics and mass model) and only the
effects, actuators and integrator are added here (MuJoCo's MjSpec); with
`--model XML` as well, from that file, whose joint attributes are kept (to
simulate `sdrs calibrate`'s `calibrated.xml` under the scene's controller); without
it, the model is built by this script from the export (kept as a second,
independent construction).

Supported scenes: one robot, revolute and prismatic joints, sine and constant
targets, no contact. Output: CSV `t,<joint>…` at `--period` (s) with
Gaussian noise `--noise` (rad or m), the columns `sdrs simulate` writes.
"""

import argparse
import csv
import json
import os
import sys

import mujoco
import numpy as np
import yaml

from scene_signals import rpy_matrix, signal as scene_signal



def mat_quat(m):
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, m.reshape(-1))
    return q



def solid_inertial(name, link, hulls):
    """Mass, COM and inertia (about the COM) of a `solid` link: each hull a
    uniform solid (trimesh's polyhedral integrals), overlapping hulls
    superposed, as `sdrs::model::mass` does."""
    try:
        import trimesh
    except ImportError:
        fail(f"link {name!r}: the `solid` mass model needs trimesh")
    meshes = [trimesh.convex.convex_hull(np.asarray(h, dtype=float)) for h in hulls]
    volume = sum(mesh.volume for mesh in meshes)
    density = link["mass_model"].get("density")
    if density is None:
        density = link["mass"] / volume
    parts = []
    for mesh in meshes:
        mesh.density = density
        p = mesh.mass_properties
        parts.append((p["mass"], np.asarray(p["center_mass"]), np.asarray(p["inertia"])))
    m = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / m
    inertia = sum(p[2] + p[0] * (np.dot(p[1] - com, p[1] - com) * np.eye(3) - np.outer(p[1] - com, p[1] - com))
                  for p in parts)
    return m, com, inertia


def fail(msg):
    sys.exit(f"error: {msg}")


def signal(sig, t):
    try:
        return scene_signal(sig, t)
    except ValueError as e:
        fail(str(e))


def build(scene, hulls, args):
    robots = scene.get("robots", [])
    if len(robots) != 1 or scene.get("objects") or scene.get("contact") or scene.get("ground"):
        fail("the converter supports one robot without contact, objects or ground")
    robot = robots[0]
    links = robot["links"]
    exported = {l["name"]: l for l in hulls["links"] if l["robot"] == robot["name"]}
    base = robot.get("base", {})
    g = scene.get("gravity", [0, 0, -9.81])
    dt_sdrs = scene["dt"]
    lines = [
        '<mujoco model="sdrs">',
        f'  <option timestep="{args.timestep}" gravity="{g[0]} {g[1]} {g[2]}" integrator="{args.integrator}"/>',
        "  <worldbody>",
    ]
    children = {}
    for l in links:
        children.setdefault(l.get("parent"), []).append(l)
    joints = []

    def body(l, indent):
        name = l["name"]
        if name not in exported:
            fail(f"link {name!r} is not in hulls.json")
        verts = np.array([v for h in exported[name]["hulls"] for v in h])
        model = (l.get("mass_model") or {"type": "vertices"})["type"]
        if model == "given":
            mm = l["mass_model"]
            m = float(mm["mass"])
            com = np.array(mm["com"], dtype=float)
            ixx, ixy, ixz, iyy, iyz, izz = mm["inertia"]
            inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
        elif model == "solid":
            m, com, inertia = solid_inertial(name, l, exported[name]["hulls"])
        else:
            if "mass" in l:
                rho = np.full(len(verts), l["mass"] / len(verts))
            elif "vertex_mass" in l:
                rho = np.full(len(verts), l["vertex_mass"])
            else:
                fail(f"link {name!r}: neither mass nor vertex_mass")
            m = rho.sum()
            com = (rho[:, None] * verts).sum(0) / m
            r = verts - com
            inertia = sum(w * (np.dot(x, x) * np.eye(3) - np.outer(x, x)) for w, x in zip(rho, r))
        j = l["joint"]
        o = j.get("origin", {})
        xyz = o.get("xyz", [0, 0, 0])
        q = mat_quat(rpy_matrix(*o.get("rpy", [0, 0, 0])))
        jn = j.get("name", name)
        pad = " " * indent
        out = [f'{pad}<body name="{name}" pos="{xyz[0]} {xyz[1]} {xyz[2]}" quat="{q[0]} {q[1]} {q[2]} {q[3]}">']
        fi = inertia
        out.append(
            f'{pad}  <inertial pos="{com[0]} {com[1]} {com[2]}" mass="{m}" '
            f'fullinertia="{fi[0,0]} {fi[1,1]} {fi[2,2]} {fi[0,1]} {fi[0,2]} {fi[1,2]}"/>'
        )
        kind = j["type"]
        if kind in ("revolute", "prismatic"):
            a = j["axis"]
            jt = "hinge" if kind == "revolute" else "slide"
            out.append(
                f'{pad}  <joint name="{jn}" type="{jt}" axis="{a[0]} {a[1]} {a[2]}" '
                f'damping="{args.damping}" frictionloss="{args.frictionloss}" armature="{args.armature}" limited="false"/>'
            )
            joints.append(jn)
        elif kind != "fixed":
            fail(f"joint {jn!r}: type {kind} is not supported")
        for c in children.get(name, []):
            out += body(c, indent + 2)
        out.append(f"{pad}</body>")
        return out

    bx = base.get("xyz", [0, 0, 0])
    bq = mat_quat(rpy_matrix(*base.get("rpy", [0, 0, 0])))
    lines.append(f'    <body name="base" pos="{bx[0]} {bx[1]} {bx[2]}" quat="{bq[0]} {bq[1]} {bq[2]} {bq[3]}">')
    for l in children.get(None, []):
        lines += body(l, 6)
    lines += ["    </body>", "  </worldbody>", "  <actuator>"]
    for jn in joints:
        lines.append(f'    <motor name="{jn}" joint="{jn}" gear="1" ctrllimited="false"/>')
    lines += ["  </actuator>", "</mujoco>"]
    return "\n".join(lines), joints, dt_sdrs


def from_sdrs(scene_path, scene, args):
    """The robot as `sdrs export-mjcf` writes it, plus the effects on every
    hinge/slide joint and one motor per joint (MjSpec edits)."""
    import subprocess
    import tempfile
    if args.model:
        spec = mujoco.MjSpec.from_file(args.model)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            xml = os.path.join(tmp, "model.xml")
            r = subprocess.run([args.sdrs, "export-mjcf", scene_path, "--out", xml],
                               capture_output=True, text=True)
            if r.returncode != 0:
                fail(f"sdrs export-mjcf failed: {r.stderr.strip()}")
            spec = mujoco.MjSpec.from_file(xml)
    spec.option.timestep = args.timestep
    spec.option.integrator = {"implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                              "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                              "RK4": mujoco.mjtIntegrator.mjINT_RK4,
                              "Euler": mujoco.mjtIntegrator.mjINT_EULER}[args.integrator]
    joints = []
    for j in spec.joints:
        if j.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            if not args.model:  # --model keeps the file's own joint attributes
                j.damping = [args.damping, 0.0, 0.0]  # MuJoCo 4: damping polynomial
                j.frictionloss = args.frictionloss
                j.armature = args.armature
            joints.append(j.name)
        else:
            fail(f"joint {j.name!r}: only revolute and prismatic joints are supported")
    for jn in joints:
        spec.add_actuator(name=jn, target=jn, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    return spec, joints, float(scene["dt"])


def check_poses(model, data, export_dir, robot_links):
    """Link poses at θ^0 against the SDRS export (step 0 of poses.csv)."""
    path = os.path.join(export_dir, "poses.csv")
    worst = 0.0
    with open(path) as f:
        for row in csv.DictReader(f):
            if row["step"] != "0":
                continue
            name = robot_links[int(row["link"])]
            b = model.body(name).id
            t = np.array([float(row[k]) for k in ("t0", "t1", "t2")])
            r = np.array([[float(row[f"a{i}{j}"]) for j in range(3)] for i in range(3)])
            worst = max(worst, np.abs(data.xpos[b] - t).max(), np.abs(data.xmat[b].reshape(3, 3) - r).max())
    if worst > 1e-9:
        fail(f"converted kinematics disagree with {path}: {worst:.3e}")
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("export_dir")
    ap.add_argument("--out", required=True)
    ap.add_argument("--mjcf")
    ap.add_argument("--sdrs", help="the sdrs binary: take the MJCF from `sdrs export-mjcf`")
    ap.add_argument("--model", help="with --sdrs: take the MJCF from this file instead (e.g. "
                    "`sdrs calibrate`'s calibrated.xml), keeping its joint attributes; "
                    "--damping/--frictionloss/--armature are then not applied")
    for k in ("damping", "frictionloss", "armature"):
        ap.add_argument(f"--{k}", type=float, default=0.0)
    ap.add_argument("--gain", type=float, default=1.0)
    ap.add_argument("--duration", type=float, default=1.2)
    ap.add_argument("--period", type=float, default=0.01)
    ap.add_argument("--noise", type=float, default=1e-4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timestep", type=float, default=1e-4)
    ap.add_argument("--integrator", default="implicitfast", choices=["implicitfast", "implicit", "RK4", "Euler"],
                    help="MuJoCo integrator (default implicitfast)")
    args = ap.parse_args()
    with open(args.scene) as f:
        scene = yaml.safe_load(f)
    with open(os.path.join(args.export_dir, "hulls.json")) as f:
        hulls = json.load(f)
    if args.sdrs:
        spec, joints, dt_sdrs = from_sdrs(args.scene, scene, args)
        model = spec.compile()
        if args.mjcf:
            with open(args.mjcf, "w") as f:
                f.write(spec.to_xml())
    else:
        xml, joints, dt_sdrs = build(scene, hulls, args)
        if args.mjcf:
            with open(args.mjcf, "w") as f:
                f.write(xml)
        model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    robot = scene["robots"][0]
    init = robot.get("initial", {})
    for jn in joints:
        adr = model.joint(jn).qposadr[0]
        dof = model.joint(jn).dofadr[0]
        data.qpos[adr] = (init.get(jn, {}).get("q") or [0.0])[0]
        data.qvel[dof] = (init.get(jn, {}).get("qdot") or [0.0])[0]
    mujoco.mj_forward(model, data)
    check_poses(model, data, args.export_dir, [l["name"] for l in hulls["links"]])
    ctrl = robot.get("controller", {})
    gains = ctrl.get("gains", {})
    targets = ctrl.get("targets", {})
    rng = np.random.default_rng(args.seed)
    names = joints
    rows = []
    next_sample = 0.0
    steps = int(round(args.duration / args.timestep))
    for k in range(steps + 1):
        t = k * args.timestep
        if t >= next_sample - 1e-12:
            rows.append([t] + [data.qpos[model.joint(j).qposadr[0]] + args.noise * rng.standard_normal() for j in names])
            next_sample += args.period
        if k == steps:
            break
        for jn in joints:
            if jn not in targets:
                continue
            kp = gains.get(jn, {}).get("kp", ctrl.get("kp", 0.0))
            kd = gains.get(jn, {}).get("kd", ctrl.get("kd", 0.0))
            qs, vs = signal(targets[jn], t)
            q = data.qpos[model.joint(jn).qposadr[0]]
            v = data.qvel[model.joint(jn).dofadr[0]]
            data.ctrl[model.actuator(jn).id] = args.gain * (2 * kp * (qs - q) + 2 * kd / dt_sdrs * (vs - v))
        mujoco.mj_step(model, data)
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t"] + names)
        for r in rows:
            w.writerow([repr(float(x)) for x in r])


if __name__ == "__main__":
    main()
