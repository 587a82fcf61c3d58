#!/usr/bin/env python3
"""PD tracking of an SDRS robot against MuJoCo, contact-free: error vs Δt.

    python tools/check/pd_vs_mujoco.py SCENE.yaml --sdrs target/release/sdrs \
        [--duration 1.0] [--dts 1e-2,3e-3,1e-3,3e-4,1e-4] [--mj-timestep 2e-5] \
        [--gravity 0 0 -9.81] [--work DIR] [--json out.json]

SCENE has one robot (revolute, prismatic, ball and free joints) with the
scene's PD controller (constant and sine targets). The comparison scene
drops contact, ground, obstacles and objects. MuJoCo gets the robot from
`sdrs export-mjcf` (same kinematics, masses, COMs and inertias) and the
same controller, evaluated by MuJoCo's control callback at every step, with
its `implicit` integrator at `--mj-timestep` (default 1e-6 s, 100× below the
smallest SDRS Δt; the damping part is MuJoCo's implicit joint damping, the
rest an applied force):

    τ = 2 k_p (θ* − θ) + c (θ̇* − θ̇),   c = 2 k_d / Δt_scene,

the continuous-time law of SDRS's stable-PD term (src/energy/pd.rs; its
damping force is (2 k_d/Δt)(θ̇* − θ̇)). To keep that law while Δt changes,
every SDRS run uses k_d(Δt) = k_d · Δt/Δt_scene, so c is the same at every
Δt and both engines integrate one ODE. Printed per Δt: the largest
difference over `--duration` (sampled every 0.01 s) of the joint angles
(revolute and ball coordinates, rad), of a free base's position (m) and
orientation (rad, angle of R_sdrsᵀ R_mujoco), and the observed order
log(e₁/e₂)/log(Δt₁/Δt₂); SDRS's scheme is first order. Exit 2 on bad input.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import mujoco
    import numpy as np
    import yaml

    from scene_signals import rpy_matrix, signal as scene_signal
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e.name}", file=sys.stderr)
    sys.exit(3)


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(2)


def signal(sig, t):
    try:
        return scene_signal(sig, t)
    except ValueError as e:
        fail(str(e))


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"{' '.join(map(str, cmd))} failed:\n{r.stderr}")
    return r.stdout



def rotvec_matrix(v):
    th = float(np.linalg.norm(v))
    if th < 1e-300:
        return np.eye(3)
    k = np.asarray(v) / th
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * kx + (1 - math.cos(th)) * kx @ kx



def origin(o):
    o = o or {}
    return rpy_matrix(*o.get("rpy", [0, 0, 0])), np.array(o.get("xyz", [0, 0, 0]), dtype=float)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--sdrs", required=True)
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--dts", default="1e-2,3e-3,1e-3,3e-4,1e-4")
    ap.add_argument("--mj-timestep", type=float, default=1e-6)
    ap.add_argument("--gravity", type=float, nargs=3)
    ap.add_argument("--sine", type=float, nargs=2, metavar=("AMP", "FREQ"),
                    help="replace every revolute joint's target by AMP·sin(2π FREQ t + k) "
                         "(k: the joint's index), e.g. to drive an imported arm")
    ap.add_argument("--work")
    ap.add_argument("--json")
    a = ap.parse_args()
    with open(a.scene) as f:
        scene = yaml.safe_load(f)
    robots = scene.get("robots", [])
    if len(robots) != 1:
        fail("the scene must have exactly one robot")
    for k in ("contact", "ground", "obstacles", "objects", "effects"):
        scene.pop(k, None)
    if a.gravity:
        scene["gravity"] = a.gravity
    robot = robots[0]
    if a.sine:
        ctl = robot.setdefault("controller", {})
        ctl["targets"] = {}
        for k, l in enumerate(robot["links"]):
            if l["joint"]["type"] == "revolute":
                jn = l["joint"].get("name") or l["name"]
                ctl["targets"][jn] = {"type": "sine", "offset": 0.0, "terms": [
                    {"amplitude": a.sine[0], "frequency": a.sine[1], "phase": float(k)}]}
    dt0 = float(scene["dt"])
    ctl = robot.get("controller", {}) or {}
    work = a.work or tempfile.mkdtemp(prefix="pd_vs_mujoco_")
    os.makedirs(work, exist_ok=True)
    base_scene = os.path.join(work, "scene.yaml")
    with open(base_scene, "w") as f:
        yaml.safe_dump(scene, f)
    xml = os.path.join(work, "model.xml")
    run([a.sdrs, "export-mjcf", base_scene, "--out", xml, "--force"])

    # Controller as MuJoCo sees it: per (mujoco joint, dof) the target and gains.
    joints = {l.get("joint", {}).get("name") or l["name"]: l["joint"] for l in robot["links"]}
    gains = ctl.get("gains", {}) or {}
    kp0, kd0 = float(ctl.get("kp", 0.0)), float(ctl.get("kd", 0.0))
    m = mujoco.MjModel.from_xml_path(xml)
    m.opt.timestep = a.mj_timestep
    # The damping c is stiff for light links (c Δt / I ≫ 1): MuJoCo treats
    # joint damping implicitly with its `implicit` integrator, so c goes into
    # dof_damping and only 2k_p(θ* − θ) + c θ̇* is an applied force.
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICIT
    d = mujoco.MjData(m)
    controlled = []  # (dof address, signal, kp, c)
    for jname, sigs in (ctl.get("targets") or {}).items():
        if jname not in joints:
            fail(f"controller target for unknown joint {jname!r}")
        g = gains.get(jname, {}) or {}
        kp = float(g.get("kp", kp0))
        kd = float(g.get("kd", kd0))
        kind = joints[jname]["type"]
        sigs = sigs if isinstance(sigs, list) else [sigs]
        names = [jname] if kind in ("revolute", "prismatic") else [f"{jname}_{k}" for k in range(len(sigs))]
        if kind not in ("revolute", "prismatic", "ball"):
            fail(f"joint {jname!r}: PD targets on {kind} joints are not compared")
        for n, s in zip(names, sigs):
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n)
            if j < 0:
                fail(f"joint {n!r} missing from the exported model")
            controlled.append((int(m.jnt_dofadr[j]), s, kp, 2.0 * kd / dt0))
            m.dof_damping[m.jnt_dofadr[j]] = 2.0 * kd / dt0

    def control(model, data):
        data.qfrc_applied[:] = 0.0
        for adr, s, kp, c in controlled:
            th, thd = signal(s, data.time)
            qadr = model.jnt_qposadr[model.dof_jntid[adr]]
            # c (θ̇* − θ̇): −c θ̇ is MuJoCo's (implicit) joint damping.
            data.qfrc_applied[adr] = 2.0 * kp * (th - data.qpos[qadr]) + c * thd

    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.set_mjcb_control(control)
    period = 0.01
    nsamp = int(round(a.duration / period))
    ref = {}
    free = []  # (scene joint, qpos address)
    for j in range(m.njnt):
        n = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE):
            free.append((n, int(m.jnt_qposadr[j])))
        elif int(m.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            ref[n] = []
        else:
            fail(f"joint {n!r}: ball joints (spherical) are not compared")
    base = {n: [] for n, _ in free}
    # Two-hinge `ball` joints are exported as NAME_0, NAME_1; SDRS columns NAME:0, NAME:1.
    column = {f"{jn}_{k}": f"{jn}:{k}" for jn, j in joints.items() if j["type"] == "ball" for k in (0, 1)}
    steps_per = int(round(period / a.mj_timestep))
    try:
        for k in range(nsamp + 1):
            if k > 0:
                mujoco.mj_step(m, d, nstep=steps_per)
            for n in ref:
                j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n)
                ref[n].append(float(d.qpos[m.jnt_qposadr[j]]))
            for n, adr in free:
                q = d.qpos[adr:adr + 7]
                r = np.zeros(9)
                mujoco.mju_quat2Mat(r, q[3:7])
                base[n].append((q[:3].copy(), r.reshape(3, 3)))
    finally:
        mujoco.set_mjcb_control(None)

    rows = []
    prev = None
    for dt in [float(x) for x in a.dts.split(",")]:
        s = yaml.safe_load(open(base_scene))
        s["dt"] = dt
        s["steps"] = int(round(a.duration / dt))
        c2 = s["robots"][0].setdefault("controller", {})
        c2["kd"] = kd0 * dt / dt0
        for g in (c2.get("gains") or {}).values():
            if g and "kd" in g:
                g["kd"] = float(g["kd"]) * dt / dt0
        path = os.path.join(work, f"scene_dt{dt:g}.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(s, f)
        out = os.path.join(work, f"traj_dt{dt:g}.csv")
        run([a.sdrs, "simulate", path, "--out", out, "-q"])
        tr = read_csv(out)
        t = tr["t"]
        idx = [int(np.argmin(np.abs(t - k * period))) for k in range(nsamp + 1)]
        ej = 0.0
        for n, v in ref.items():
            col = column.get(n, n)
            if col not in tr:
                fail(f"column for joint {n!r} missing from the SDRS trajectory")
            ej = max(ej, float(np.max(np.abs(tr[col][idx] - np.array(v)))))
        ep, er = 0.0, 0.0
        for n, samples in base.items():
            # SDRS's free coordinates are relative to the root attachment
            # C = base · joint origin; MuJoCo's are world poses.
            rb, tb = origin(robot.get("base"))
            rj, tj = origin(joints[n].get("origin"))
            rc, tc = rb @ rj, rb @ tj + tb
            for k, (p, r) in zip(idx, samples):
                pos = rc @ np.array([tr[f"{n}:x"][k], tr[f"{n}:y"][k], tr[f"{n}:z"][k]]) + tc
                rot = rc @ rotvec_matrix([tr[f"{n}:rx"][k], tr[f"{n}:ry"][k], tr[f"{n}:rz"][k]])
                ep = max(ep, float(np.linalg.norm(pos - p)))
                cosang = (np.trace(rot.T @ r) - 1) / 2
                er = max(er, math.acos(max(-1.0, min(1.0, cosang))))
        worst = max(ej, er)
        order = None if prev is None else math.log(prev[1] / worst) / math.log(prev[0] / dt)
        rows.append({"dt": dt, "max_joint_error": ej, "max_base_position_error": ep,
                     "max_base_rotation_error": er, "order": order})
        prev = (dt, worst)
    print(f"{'dt (s)':>10} {'joints (rad)':>14} {'base pos (m)':>14} {'base rot (rad)':>15} {'order':>7}")
    for r in rows:
        o = "" if r["order"] is None else f"{r['order']:.2f}"
        print(f"{r['dt']:>10.0e} {r['max_joint_error']:>14.3e} {r['max_base_position_error']:>14.3e} "
              f"{r['max_base_rotation_error']:>15.3e} {o:>7}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"scene": a.scene, "duration": a.duration, "mj_timestep": a.mj_timestep,
                       "controlled_dofs": len(controlled), "rows": rows}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
