#!/usr/bin/env python3
"""Compare our joint-space mass matrices with MuJoCo's `mj_fullM`.

Usage: check_mass_matrix_mujoco.py MODEL.xml SAMPLES.json [--tol 1e-9]

SAMPLES.json: {"configurations": [{"qpos": {joint: [values]},
                                   "dofs": [[joint, k], ...],
                                   "M": [[...], ...]}]}
`qpos` gives MuJoCo's qpos of every joint (hinge/slide: 1 value, ball: a
quaternion w x y z, free: x y z w x y z); `dofs` names the rows/columns of
`M`: the k-th velocity of the joint (MuJoCo's `qvel` order: free = linear
velocity in the world frame, then angular velocity in the body frame; ball =
angular velocity in the body frame). The relative error per configuration
is max|M − M_mj| / max|M_mj|, where M_mj is MuJoCo's rigid-body part:
`mj_fullM` minus the joints' armature (`dof_armature`, rotor inertia on the
diagonal, which sdrs imports as the separate `armature` effect for hinge and
slide joints and reports as left out for ball and free joints).

Prints a JSON summary; exits 1 when an error exceeds --tol, 2 on bad input,
3 when mujoco is missing.
"""
import argparse
import json
import sys

try:
    import mujoco
    import numpy as np
except ImportError as e:
    print(f"missing Python package: {e.name}", file=sys.stderr)
    sys.exit(3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("samples")
    ap.add_argument("--tol", type=float, default=1e-9)
    a = ap.parse_args()
    m = mujoco.MjModel.from_xml_path(a.model)
    d = mujoco.MjData(m)
    with open(a.samples) as f:
        samples = json.load(f)["configurations"]
    worst, at, entry = 0.0, None, None
    for ci, s in enumerate(samples):
        d.qpos[:] = m.qpos0
        for name, vals in s["qpos"].items():
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j < 0:
                print(f"configuration {ci}: no joint '{name}' in MuJoCo's model", file=sys.stderr)
                return 2
            adr = m.jnt_qposadr[j]
            d.qpos[adr:adr + len(vals)] = vals
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)  # MuJoCo 4 signature: (model, data, dst)
        idx = []
        for name, k in s["dofs"]:
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j < 0:
                print(f"no joint '{name}' in MuJoCo's model", file=sys.stderr)
                return 2
            idx.append(m.jnt_dofadr[j] + k)
        if sorted(idx) != list(range(m.nv)):
            print(f"our matrix covers {len(set(idx))} of MuJoCo's {m.nv} velocities", file=sys.stderr)
            return 1
        full -= np.diag(m.dof_armature)
        ref = full[np.ix_(idx, idx)]
        ours = np.array(s["M"])
        diff = np.abs(ours - ref)
        err = float(diff.max() / np.abs(ref).max())
        if at is None or err > worst:
            r, c = np.unravel_index(int(diff.argmax()), diff.shape)
            worst, at = err, ci
            entry = {"row": s["dofs"][r], "column": s["dofs"][c],
                     "ours": float(ours[r, c]), "mujoco": float(ref[r, c])}
    print(json.dumps({"model": a.model, "configurations": len(samples), "nv": int(m.nv),
                      "max_relative_error": worst, "worst_configuration": at,
                      "worst_entry": entry if samples else None, "tol": a.tol}))
    return 1 if worst > a.tol else 0


if __name__ == "__main__":
    sys.exit(main())
