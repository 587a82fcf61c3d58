#!/usr/bin/env python3
"""Compare our forward kinematics with Pinocchio's.

Usage: check_fk_pinocchio.py ROBOT.urdf SAMPLES.json [--tol 1e-9]

SAMPLES.json (written by sdrs::import::fkcheck::fk_samples):
  {"configurations": [{"joints": {urdf_joint: [values]},
                       "links": {link: {"R": 3x3, "p": [3]}}}]}
Joint values: one number for revolute/continuous/prismatic joints, and
[x, y, z, qx, qy, qz, qw] for floating joints.

Prints a JSON summary; exits 1 with a message when a pose differs by more
than --tol (rotation entries and translation, absolute), 2 on bad input,
3 when pinocchio is missing.
"""
import json
import math
import sys

from pin_samples import load  # first: exits 3 when a package is missing

import numpy as np
import pinocchio as pin


def main():
    a, model, data, samples = load(__doc__.splitlines()[0])
    worst = (0.0, None, None)
    compared = 0
    for ci, s in enumerate(samples):
        q = pin.neutral(model)
        given = dict(s["joints"])
        for jid in range(1, model.njoints):
            name = model.names[jid]
            j = model.joints[jid]
            if name not in given:
                print(f"configuration {ci}: Pinocchio joint '{name}' has no value in the samples "
                      f"(our model lost or renamed it)", file=sys.stderr)
                return 1
            v = given.pop(name)
            if j.nq == 1:
                q[j.idx_q] = v[0]
            elif j.nq == 2 and j.nv == 1:  # continuous: (cos, sin)
                q[j.idx_q:j.idx_q + 2] = [math.cos(v[0]), math.sin(v[0])]
            elif j.nq == 7:
                q[j.idx_q:j.idx_q + 7] = v
            else:
                print(f"joint '{name}': unsupported Pinocchio joint with nq={j.nq}", file=sys.stderr)
                return 2
        if given:
            print(f"configuration {ci}: joints {sorted(given)} are not in Pinocchio's model", file=sys.stderr)
            return 1
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        for link, pose in s["links"].items():
            if not model.existFrame(link, pin.BODY):
                print(f"link '{link}' is not a body frame of Pinocchio's model", file=sys.stderr)
                return 1
            M = data.oMf[model.getFrameId(link, pin.BODY)]
            err = max(np.abs(M.rotation - np.array(pose["R"])).max(),
                      np.abs(M.translation - np.array(pose["p"])).max())
            compared += 1
            if err > worst[0]:
                worst = (err, ci, link)
    summary = {"configurations": len(samples), "poses": compared, "max_error": worst[0],
               "worst_configuration": worst[1], "worst_link": worst[2], "tol": a.tol}
    print(json.dumps(summary))
    if worst[0] > a.tol:
        print(f"FK mismatch: link '{worst[2]}' in configuration {worst[1]} differs by {worst[0]:.3e} "
              f"(> {a.tol:g})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
