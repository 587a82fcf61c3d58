#!/usr/bin/env python3
"""Compare our joint-space mass matrices with Pinocchio's CRBA.

Usage: check_mass_matrix_pinocchio.py ROBOT.urdf SAMPLES.json [--tol 1e-9]

SAMPLES.json: {"configurations": [{"joints": {urdf_joint: value},
                                   "dofs": [urdf_joint, ...],
                                   "M": [[...], ...]}]}
`dofs` names the rows/columns of `M` (1-DOF revolute/prismatic joints;
`M` is our matrix restricted to them). Pinocchio builds a fixed-base model
from the URDF; the relative error is max|M − M_pin| / max|M_pin| per
configuration.

Prints a JSON summary; exits 1 when an error exceeds --tol, 2 on bad input,
3 when pinocchio is missing.
"""
import json
import sys

from pin_samples import load  # first: exits 3 when a package is missing

import numpy as np
import pinocchio as pin


def main():
    a, model, data, samples = load(__doc__.splitlines()[0])
    worst = (0.0, None)
    for ci, s in enumerate(samples):
        q = pin.neutral(model)
        for jid in range(1, model.njoints):
            name = model.names[jid]
            j = model.joints[jid]
            if j.nq != 1:
                print(f"joint '{name}': only 1-DOF joints are compared (nq={j.nq})", file=sys.stderr)
                return 2
            if name not in s["joints"]:
                print(f"configuration {ci}: joint '{name}' has no value", file=sys.stderr)
                return 1
            q[j.idx_q] = s["joints"][name]
        full = pin.crba(model, data, q)
        full = np.triu(full) + np.triu(full, 1).T
        idx = []
        for name in s["dofs"]:
            if not model.existJointName(name):
                print(f"joint '{name}' is not in Pinocchio's model", file=sys.stderr)
                return 1
            idx.append(model.joints[model.getJointId(name)].idx_v)
        if len(idx) != model.nv:
            print(f"our matrix covers {len(idx)} of Pinocchio's {model.nv} velocities", file=sys.stderr)
            return 1
        ref = full[np.ix_(idx, idx)]
        ours = np.array(s["M"])
        err = np.abs(ours - ref).max() / np.abs(ref).max()
        if err > worst[0] or worst[1] is None:
            worst = (err, ci)
    summary = {"configurations": len(samples), "dofs": len(samples[0]["dofs"]),
               "max_relative_error": worst[0], "worst_configuration": worst[1], "tol": a.tol}
    print(json.dumps(summary))
    if worst[0] > a.tol:
        print(f"mass matrix mismatch: configuration {worst[1]} differs by {worst[0]:.3e} relative "
              f"(> {a.tol:g})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
