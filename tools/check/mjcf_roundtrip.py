#!/usr/bin/env python3
"""Round trip of an MJCF model through sdrs: the original against `sdrs import` → `sdrs
export-mjcf`, both compiled by MuJoCo (issue 32, item 6, static part).

Usage: mjcf_roundtrip.py ORIGINAL.xml EXPORTED.xml [--tol 1e-9] [--actuators]
           [--trajectory SDRS.csv [--qpos joint=value,...] [--mj-timestep 1e-5] [--traj-tol X]
            [--mj-solref T]]

Both models are put at their initial state (the original at `qpos0` with the `--qpos` values,
the export at its keyframe `initial`) and compared in the frame of the original's first body (the root; the export's body
of that name), so that where the import placed the robot (lifted onto a ground) does not matter:

- bodies by name (the export prefixes `robot/` when the scene has several robots; the massless
  frames sdrs inserts for bodies with several joints, `BODY__JOINT`, weigh 1e-12 kg and are
  skipped): mass, centre of mass and the inertia tensor about it (world axes rotated into the
  root frame: `R_rootᵀ R_i diag(I) R_iᵀ R_root`);
- joints by name (a two-hinge ball of sdrs is `NAME_0`, `NAME_1`; only imported hinge and slide
  joints are compared one to one): type, axis (and a hinge's anchor) in the root frame, range when limited,
  damping, armature, frictionloss, stiffness and springref.

Relative errors `|a − b| / max(|b|, floor)` (floors: 1e-9 kg, 1e-6 m, 1e-9 kg m², 1e-9 for the
joint coefficients). Actuators are listed from the original and reported as
`actuators_not_exported` (without `--actuators`, sdrs exports none).

`--actuators`: the servos of both models as joint-space laws `τ = F − K q − C q̇` per hinge/slide
(fixed-gain, affine-bias actuators without activation dynamics, summed per joint; the original at
ctrl 0 clamped to ctrlrange, the export at its keyframe's ctrl), relative error `servo` (floors
1, 1e-3, 1e-3); a joint the original servos and the export does not is `missing`. The export
(`sdrs export-mjcf --actuators`) writes the scene's PD as `<position kp="2 k_p" kv="2 k_d/Δt">`,
so an element-wise comparison (gear, kp) would not apply: the laws are what must be equal.

`--trajectory`: the original model simulated by MuJoCo (RK4 at `--mj-timestep`, from `qpos0`
with the `--qpos` values set — the same initial pose the sdrs scene was imported with, `--pose`)
against an `sdrs simulate` CSV of the imported scene: the largest difference of every hinge/slide
column over the CSV's times (rad or m), which must stay within `--traj-tol`.

Prints a JSON report; exits 1 when an error exceeds --tol or a body/joint is missing, 2 on bad
input, 3 when mujoco is missing.
"""
import argparse
import csv
import json
import sys

try:
    import mujoco
    import numpy as np
except ImportError as e:
    print(f"missing Python package: {e.name}", file=sys.stderr)
    sys.exit(3)


def set_qpos(m, d, qpos):
    """`qpos`: joint name → value (hinge/slide)."""
    for name, v in qpos.items():
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0:
            raise ValueError(f"--qpos: no joint {name!r}")
        d.qpos[m.jnt_qposadr[j]] = v


def load(path, key=None, qpos=None):
    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    if key is not None:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, key)
        if k >= 0:
            mujoco.mj_resetDataKeyframe(m, d, k)
    set_qpos(m, d, qpos or {})
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    return m, d


def bare(name):
    return name.split("/", 1)[1] if "/" in name else name


def root_id(m, name):
    """The body named `name` (bare names), the frame everything is compared in."""
    for b in range(1, m.nbody):
        if bare(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or "") == name:
            return b
    return None


def bodies(m, d, root):
    """name → (mass, com, inertia tensor) in the frame of body `root`."""
    r0, p0 = d.xmat[root].reshape(3, 3), d.xpos[root]
    out = {}
    for b in range(1, m.nbody):
        name = bare(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}")
        if "__" in name or m.body_mass[b] <= 1e-9:
            continue
        ri = d.ximat[b].reshape(3, 3)
        tensor = r0.T @ ri @ np.diag(m.body_inertia[b]) @ ri.T @ r0
        out[name] = (float(m.body_mass[b]), r0.T @ (d.xipos[b] - p0), tensor)
    return out


def joints(m, d, root):
    r0, p0 = d.xmat[root].reshape(3, 3), d.xpos[root]
    out = {}
    for j in range(m.njnt):
        t = int(m.jnt_type[j])
        if t not in (2, 3):  # slide, hinge
            continue
        name = bare(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}")
        v = m.jnt_dofadr[j]
        out[name] = {
            "type": t,
            "anchor": r0.T @ (d.xanchor[j] - p0),
            "axis": r0.T @ d.xaxis[j],
            "range": np.array(m.jnt_range[j]) if m.jnt_limited[j] else None,
            "damping": float(m.dof_damping[v]),
            "armature": float(m.dof_armature[v]),
            "frictionloss": float(m.dof_frictionloss[v]),
            "stiffness": float(m.jnt_stiffness[j]),
            "springref": float(m.qpos_spring[m.jnt_qposadr[j]]) if m.jnt_stiffness[j] > 0 else 0.0,
        }
    return out


def trajectory(m, csv_path, qpos, h, solref=None):
    """Largest |sdrs − MuJoCo| per joint column of `csv_path` (rad or m).
    `solref`: every geom's contact time constant (s) replaced by it (MuJoCo's
    own contact softness, to measure its share of a contact difference)."""
    with open(csv_path, newline="") as f:
        rows = list(csv.reader(f))
    header = [bare(h) for h in rows[0]]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    a = {h: data[:, i] for i, h in enumerate(header)}
    t = a["t"]
    m.opt.timestep = h
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    if solref is not None:
        m.geom_solref[:, 0] = solref
    d = mujoco.MjData(m)
    set_qpos(m, d, qpos)
    cols = {}
    for name in header:
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j >= 0 and int(m.jnt_type[j]) in (2, 3):
            cols[name] = m.jnt_qposadr[j]
    err = {c: 0.0 for c in cols}
    for k, tk in enumerate(t):
        while d.time < tk - 0.5 * h:
            mujoco.mj_step(m, d)
        for c, adr in cols.items():
            err[c] = max(err[c], abs(float(a[c][k]) - float(d.qpos[adr])))
    return err


def servos(m, d):
    """Joint name → [K, C, F]: the joint-space stiffness, damping and force at the current ctrl
    (clamped to ctrlrange when limited) of the fixed-gain, affine/no-bias actuators without
    activation dynamics on one hinge/slide: τ = F − K q − C q̇, summed over the actuators
    (K = −g² b₁, C = −g² b₂, F = g (a₀ u + b₀); `src/import/mjcf/actuators.rs`)."""
    out = {}
    for a in range(m.nu):
        if int(m.actuator_trntype[a]) not in (0, 1) or int(m.actuator_dyntype[a]) != 0:
            continue
        if int(m.actuator_gaintype[a]) != 0 or int(m.actuator_biastype[a]) not in (0, 1):
            continue
        j = int(m.actuator_trnid[a][0])
        if int(m.jnt_type[j]) not in (2, 3):
            continue
        g, a0 = float(m.actuator_gear[a][0]), float(m.actuator_gainprm[a][0])
        b = m.actuator_biasprm[a] if int(m.actuator_biastype[a]) == 1 else np.zeros(3)
        u = float(d.ctrl[a])
        if m.actuator_ctrllimited[a]:
            u = min(max(u, float(m.actuator_ctrlrange[a][0])), float(m.actuator_ctrlrange[a][1]))
        k, c, f = -g * g * float(b[1]), -g * g * float(b[2]), g * (a0 * u + float(b[0]))
        if k == 0 and c == 0:
            continue  # a motor: no force at rest
        name = bare(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}")
        s = out.setdefault(name, [0.0, 0.0, 0.0])
        s[0], s[1], s[2] = s[0] + k, s[1] + c, s[2] + f
    return out


def rel(a, b, floor):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), floor))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("original")
    ap.add_argument("exported")
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("--trajectory")
    ap.add_argument("--qpos", default="")
    ap.add_argument("--mj-timestep", type=float, default=1e-5)
    ap.add_argument("--traj-tol", type=float, default=1e-2)
    ap.add_argument("--mj-solref", type=float,
                    help="MuJoCo's contact time constant for every geom (default: the model's)")
    ap.add_argument("--actuators", action="store_true",
                    help="compare the servos (K, C, F per joint) of the original at ctrl 0 and "
                         "the export at its keyframe (export-mjcf --actuators)")
    a = ap.parse_args()
    qpos = {k: float(v) for k, v in (p.split("=") for p in a.qpos.split(",") if p)}
    try:
        mo, do = load(a.original, qpos=qpos)
        me, de = load(a.exported, "initial")
    except Exception as e:  # the compiler's message
        print(f"cannot compile: {e}", file=sys.stderr)
        return 2
    name = mujoco.mj_id2name(mo, mujoco.mjtObj.mjOBJ_BODY, 1) or "body1"
    ro, re_ = 1, root_id(me, name)
    if re_ is None:
        print(f"the export has no body {name!r} (the original's root)", file=sys.stderr)
        return 2
    bo, be = bodies(mo, do, ro), bodies(me, de, re_)
    jo, je = joints(mo, do, ro), joints(me, de, re_)
    errors = {"mass": 0.0, "com": 0.0, "inertia": 0.0, "joint_frame": 0.0, "range": 0.0,
              "joint_coefficients": 0.0}
    worst = {}
    missing = []

    def note(key, e, what):
        if e > errors[key]:
            errors[key], worst[key] = e, what

    for name, (mass, com, tensor) in bo.items():
        if name not in be:
            missing.append(f"body {name}")
            continue
        m2, c2, t2 = be[name]
        note("mass", rel(m2, mass, 1e-9), name)
        note("com", rel(c2, com, 1e-6), name)
        note("inertia", rel(t2, tensor, 1e-9), name)
    for name, j in jo.items():
        k = je.get(name)
        if k is None:
            missing.append(f"joint {name}")
            continue
        if k["type"] != j["type"]:
            missing.append(f"joint {name}: type {k['type']} vs {j['type']}")
        # A slide's anchor does not enter its motion: axis only.
        e = rel(k["axis"], j["axis"], 1.0)
        if j["type"] == 3:
            e = max(e, rel(k["anchor"], j["anchor"], 1e-6))
        note("joint_frame", e, name)
        if j["range"] is not None:
            if k["range"] is None:
                missing.append(f"joint {name}: range")
            else:
                note("range", rel(k["range"], j["range"], 1e-9), name)
        for c in ("damping", "armature", "frictionloss", "stiffness", "springref"):
            note("joint_coefficients", rel(k[c], j[c], 1e-9), f"{name}.{c}")
    actuators = [mujoco.mj_id2name(mo, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or f"actuator{i}"
                 for i in range(mo.nu)]
    servo = None
    if a.actuators:
        so, se = servos(mo, do), servos(me, de)
        errors["servo"] = 0.0
        for name, v in so.items():
            if name not in se:
                missing.append(f"servo on {name}")
                continue
            # Floors: 1 N·m/rad, 1e-3 N·m·s/rad, 1e-3 N·m (a zero force or damping).
            for i, floor in enumerate((1.0, 1e-3, 1e-3)):
                note("servo", rel(se[name][i], v[i], floor), f"{name}.{'KCF'[i]}")
        servo = {"original": so, "exported": se}
    ok = not missing and all(e <= a.tol for e in errors.values())
    traj = None
    if a.trajectory:
        traj = trajectory(mujoco.MjModel.from_xml_path(a.original), a.trajectory, qpos,
                          a.mj_timestep, a.mj_solref)
        ok = ok and bool(traj) and max(traj.values()) <= a.traj_tol
    print(json.dumps({
        "trajectory": traj, "traj_tol": a.traj_tol,
        "original": a.original, "exported": a.exported, "bodies": len(bo), "joints": len(jo),
        "errors": errors, "worst": worst, "missing": missing,
        "actuators_not_exported": actuators, "servo": servo, "tol": a.tol, "ok": ok,
    }, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
