#!/usr/bin/env python3
"""Compile an MJCF model with MuJoCo and print what `sdrs import` needs as JSON.

Usage: mjcf_dump.py MODEL.xml [--qpos0]

MuJoCo's own compiler resolves everything MJCF leaves implicit (default
classes, `childclass`, `<compiler angle/eulerseq/meshdir>`, `fromto`,
`<include>`, frames, inertias from geoms, mesh scaling and re-centring), so
the numbers printed here are the model MuJoCo simulates:

- bodies in tree order (parents first): name, parent index (-1 = world),
  `pos`/`quat` in the parent's frame, mass, `ipos`/`iquat` (inertial frame
  in the body frame) and the principal moments `inertia`;
- per body its joints in MuJoCo's order: type (free|ball|slide|hinge),
  anchor `pos` and unit `axis` in the body frame, `range` (null when not
  limited), damping, armature, frictionloss, stiffness, springref, ref;
- geoms (world geoms under body -1): type, `size`, `pos`/`quat` in the body
  frame, contype/conaffinity/group, friction; mesh geoms carry the
  compiled mesh's vertices and faces in the geom frame;
- actuators: name, kind (motor|position|velocity|general, from MuJoCo's
  gain/bias types and parameters), the joint it drives (null for other
  transmissions), gear, kp, kv, ctrlrange and forcerange (null when not
  limited), `transmission` (joint|jointinparent|slidercrank|tendon|site|body)
  and the name of its `target`, `dyntype`, `gaintype`, `biastype` and the
  first three `gainprm`/`biasprm` (the import maps fixed-gain, affine-bias
  actuators on a hinge or slide to the scene's PD controller:
  `src/import/mjcf/actuators.rs`);
- `exclude`: MuJoCo's compiled `<contact><exclude>` body pairs (body
  indices as in `bodies`, -1 = world), decoded from `exclude_signature`
  (`(body1 << 16) + body2`);
- `option`: gravity and timestep; `unsupported`: counts of what the
  importer leaves out (explicit contact pairs, tendons, equality
  constraints, height fields, sensors, sites, keyframes, cameras, lights,
  mocap bodies, skins, flexes), one import note per kind present.

Exit codes: 0 ok, 2 the model does not compile (MuJoCo's message, which
names the element and line, is printed on stderr), 3 mujoco missing.
"""
import json
import sys

try:
    import mujoco
    import numpy as np
except ImportError as e:  # pragma: no cover - exercised through sdrs
    print(f"missing Python package: {e.name}", file=sys.stderr)
    sys.exit(3)

JOINT_TYPES = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}
TRN_TYPES = {0: "joint", 1: "jointinparent", 2: "slidercrank", 3: "tendon", 4: "site", 5: "body"}
DYN_TYPES = {0: "none", 1: "integrator", 2: "filter", 3: "filterexact", 4: "muscle", 5: "user"}
GAIN_TYPES = {0: "fixed", 1: "affine", 2: "muscle", 3: "user"}
BIAS_TYPES = {0: "none", 1: "affine", 2: "muscle", 3: "user"}
_O = mujoco.mjtObj
# The object an actuator's transmission acts on, by transmission type.
TRN_TARGETS = {0: _O.mjOBJ_JOINT, 1: _O.mjOBJ_JOINT, 2: _O.mjOBJ_SITE, 3: _O.mjOBJ_TENDON,
               4: _O.mjOBJ_SITE, 5: _O.mjOBJ_BODY}
GEOM_TYPES = {0: "plane", 1: "hfield", 2: "sphere", 3: "capsule", 4: "ellipsoid",
              5: "cylinder", 6: "box", 7: "mesh", 8: "sdf"}


def name_of(m, kind, i, fallback):
    n = mujoco.mj_id2name(m, kind, i)
    return n if n else fallback


def floats(a):
    return [float(x) for x in np.asarray(a).reshape(-1)]


def main():
    if len(sys.argv) < 2:
        print(__doc__.splitlines()[2], file=sys.stderr)
        return 2
    path = sys.argv[1]
    try:
        m = mujoco.MjModel.from_xml_path(path)
    except Exception as e:  # mujoco raises ValueError with the compiler's message
        print(f"{path}: MuJoCo cannot compile the model: {str(e).strip()}", file=sys.stderr)
        return 2
    bodies = []
    for b in range(1, m.nbody):
        joints = []
        for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
            jt = JOINT_TYPES[int(m.jnt_type[j])]
            qa = m.jnt_qposadr[j]
            joints.append({
                "name": name_of(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"joint{j}"),
                "type": jt,
                "pos": floats(m.jnt_pos[j]),
                "axis": floats(m.jnt_axis[j]),
                "range": floats(m.jnt_range[j]) if m.jnt_limited[j] else None,
                "damping": float(m.dof_damping[m.jnt_dofadr[j]]),
                "armature": float(m.dof_armature[m.jnt_dofadr[j]]),
                "frictionloss": float(m.dof_frictionloss[m.jnt_dofadr[j]]),
                "stiffness": float(m.jnt_stiffness[j]),
                "springref": floats(m.qpos_spring[qa:qa + {"free": 7, "ball": 4}.get(jt, 1)]),
                "qpos0": floats(m.qpos0[qa:qa + {"free": 7, "ball": 4}.get(jt, 1)]),
            })
        bodies.append({
            "name": name_of(m, mujoco.mjtObj.mjOBJ_BODY, b, f"body{b}"),
            "parent": int(m.body_parentid[b]) - 1,
            "pos": floats(m.body_pos[b]),
            "quat": floats(m.body_quat[b]),
            "mass": float(m.body_mass[b]),
            "ipos": floats(m.body_ipos[b]),
            "iquat": floats(m.body_iquat[b]),
            "inertia": floats(m.body_inertia[b]),
            "mocap": bool(m.body_mocapid[b] >= 0),
            "joints": joints,
        })
    geoms = []
    for g in range(m.ngeom):
        gt = GEOM_TYPES.get(int(m.geom_type[g]), str(int(m.geom_type[g])))
        geom = {
            "name": name_of(m, mujoco.mjtObj.mjOBJ_GEOM, g, f"geom{g}"),
            "body": int(m.geom_bodyid[g]) - 1,
            "type": gt,
            "size": floats(m.geom_size[g]),
            "pos": floats(m.geom_pos[g]),
            "quat": floats(m.geom_quat[g]),
            "contype": int(m.geom_contype[g]),
            "conaffinity": int(m.geom_conaffinity[g]),
            "group": int(m.geom_group[g]),
            "friction": float(m.geom_friction[g][0]),
        }
        if gt == "mesh":
            k = int(m.geom_dataid[g])
            va, vn = m.mesh_vertadr[k], m.mesh_vertnum[k]
            fa, fn = m.mesh_faceadr[k], m.mesh_facenum[k]
            geom["mesh"] = {
                "name": name_of(m, mujoco.mjtObj.mjOBJ_MESH, k, f"mesh{k}"),
                "vertices": np.asarray(m.mesh_vert[va:va + vn], dtype=float).tolist(),
                "faces": np.asarray(m.mesh_face[fa:fa + fn], dtype=int).tolist(),
            }
        geoms.append(geom)
    actuators = []
    for a in range(m.nu):
        gain, bias = int(m.actuator_gaintype[a]), int(m.actuator_biastype[a])
        gp, bp = m.actuator_gainprm[a], m.actuator_biasprm[a]
        kind = "general"
        if int(m.actuator_dyntype[a]) == 0 and gain == 0:
            if bias == 0:
                kind = "motor"
            elif bias == 1 and bp[0] == 0 and bp[1] == -gp[0] and bp[2] <= 0:
                kind = "position"
            elif bias == 1 and bp[0] == 0 and bp[1] == 0 and bp[2] == -gp[0]:
                kind = "velocity"
        joint = None
        trn, tid = int(m.actuator_trntype[a]), int(m.actuator_trnid[a][0])
        if trn in (0, 1):  # mjTRN_JOINT, mjTRN_JOINTINPARENT
            joint = name_of(m, mujoco.mjtObj.mjOBJ_JOINT, tid, f"joint{tid}")
        target_kind = TRN_TARGETS.get(trn)
        target = name_of(m, target_kind, tid, f"#{tid}") if target_kind is not None else None
        actuators.append({
            "name": name_of(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a, f"actuator{a}"),
            "kind": kind,
            "joint": joint,
            "gear": float(m.actuator_gear[a][0]),
            "kp": float(gp[0]) if kind == "position" else None,
            "kv": float(-bp[2]) + 0.0 if kind == "position" else (float(gp[0]) if kind == "velocity" else None),
            "ctrlrange": floats(m.actuator_ctrlrange[a]) if m.actuator_ctrllimited[a] else None,
            "forcerange": floats(m.actuator_forcerange[a]) if m.actuator_forcelimited[a] else None,
            "transmission": TRN_TYPES.get(trn, str(trn)),
            "target": target,
            "dyntype": DYN_TYPES.get(int(m.actuator_dyntype[a]), str(int(m.actuator_dyntype[a]))),
            "gaintype": GAIN_TYPES.get(gain, str(gain)),
            "biastype": BIAS_TYPES.get(bias, str(bias)),
            "gainprm": floats(gp[:3]),
            "biasprm": floats(bp[:3]),
        })
    exclude = [[int(sig) >> 16, int(sig) & 0xFFFF] for sig in m.exclude_signature]
    out = {
        "file": path,
        "model": m.names[:m.names.index(b"\0")].decode() if m.names else "",
        "option": {"gravity": floats(m.opt.gravity), "timestep": float(m.opt.timestep)},
        "bodies": bodies,
        "geoms": geoms,
        "actuators": actuators,
        "exclude": [[a - 1, b - 1] for a, b in exclude],
        "unsupported": {
            "explicit contact pairs (<contact><pair>)": int(m.npair),
            "tendons": int(m.ntendon),
            "equality constraints": int(m.neq),
            "height fields": int(m.nhfield),
            "sensors (<sensor>; the scene records the state, not sensor readings)": int(m.nsensor),
            "sites (<site>)": int(m.nsite),
            "keyframes (<key>; the scene starts at qpos0, or at --pose)": int(m.nkey),
            "cameras": int(m.ncam),
            "lights": int(m.nlight),
            "mocap bodies": int(m.nmocap),
            "skins": int(m.nskin),
            "flexes (deformable bodies)": int(m.nflex),
        },
    }
    json.dump(out, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())
