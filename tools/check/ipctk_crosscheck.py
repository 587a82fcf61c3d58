#!/usr/bin/env python3
"""Reference values from IPC Toolkit (ipctk, pinned in tools/setup/requirements.txt)
for the cross-check of the IPC baseline (baselines/ipc/tests/ipctk_crosscheck.rs).

Reads a JSON job on stdin and writes the results as JSON to the file named
by the first argument (stdout without one):

- primitives: point-triangle ("pt") / edge-edge ("ee") stencils x (4 points),
  dhat (m). Potential P = b(d, dhat^2) with d the squared distance
  (ipctk's distance functions, AUTO type) and ipctk's log barrier; edge-edge
  pairs are multiplied by ipctk's mollifier with eps_x from the same
  (rigid, so rest = current) positions. Value, gradient (12) and exact
  Hessian (12x12, no PSD projection) by the product and chain rules on
  ipctk's own derivatives.
- meshes: two triangle meshes (va, fa, vb, fb), dhat: ipctk's
  BarrierPotential(dhat, stiffness 1) over NormalCollisions between the two
  meshes only (the combined mesh's minus each mesh's own); value and vertex
  gradient.
- ccd: linear trajectories x0 -> x1 of pt/ee stencils: ipctk's
  TightInclusionCCD hit flag and time of impact (minimum distance 0).
- friction: IPC's smoothed f0, f1 at (y, eps).
- friction_meshes: two triangle meshes at the lagged positions (va, fa, vb,
  fb), the displacement du of every vertex over the step, dhat, kappa, mu
  and eps (= eps_v dt, m): ipctk's TangentialCollisions built at the lagged
  positions from NormalCollisions and BarrierPotential(dhat, kappa) with
  friction coefficient mu, and FrictionPotential(eps) evaluated on the
  displacements, i.e. sum over contacts of mu lambda f0(|T^T u|; eps);
  value and gradient w.r.t. the displacements, between the two meshes only.
"""
import json
import sys

import numpy as np
import ipctk


def primitive(p):
    x = [np.array(v, dtype=float) for v in p["x"]]
    dhat2 = p["dhat"] ** 2
    if p["kind"] == "pt":
        d = ipctk.point_triangle_distance(*x)
        gd = ipctk.point_triangle_distance_gradient(*x)
        hd = ipctk.point_triangle_distance_hessian(*x)
    else:
        d = ipctk.edge_edge_distance(*x)
        gd = ipctk.edge_edge_distance_gradient(*x)
        hd = ipctk.edge_edge_distance_hessian(*x)
    b = ipctk.barrier(d, dhat2)
    b1 = ipctk.barrier_first_derivative(d, dhat2)
    b2 = ipctk.barrier_second_derivative(d, dhat2)
    val, grad = b, b1 * gd
    hess = b2 * np.outer(gd, gd) + b1 * hd
    if p["kind"] == "ee":
        eps_x = ipctk.edge_edge_mollifier_threshold(*x)
        m = ipctk.edge_edge_mollifier(*x, eps_x)
        gm = ipctk.edge_edge_mollifier_gradient(*x, eps_x)
        hm = ipctk.edge_edge_mollifier_hessian(*x, eps_x)
        hess = m * hess + np.outer(gm, grad) + np.outer(grad, gm) + val * hm
        grad = m * grad + val * gm
        val = m * val
    return {"d": d, "value": val, "grad": list(grad), "hess": [list(r) for r in hess]}


def edges_of(faces):
    e = set()
    for f in faces:
        for k in range(3):
            a, b = f[k], f[(k + 1) % 3]
            e.add((min(a, b), max(a, b)))
    return np.array(sorted(e), dtype=np.int32)


def potential(v, f, dhat):
    v = np.asfortranarray(v)
    f = np.asarray(f, dtype=np.int32)
    mesh = ipctk.CollisionMesh(v, np.asfortranarray(edges_of(f)), np.asfortranarray(f))
    col = ipctk.NormalCollisions()
    col.build(mesh, v, dhat)
    pot = ipctk.BarrierPotential(dhat, 1.0)
    return pot(col, mesh, v), np.asarray(pot.gradient(col, mesh, v)), len(col)


def mesh_pair(m):
    # Only pairs between the two meshes: the combined mesh's potential minus
    # each mesh's own (no Python can_collide callback, which ipctk calls from
    # its worker threads and which dominated and could hang).
    va, vb = np.array(m["va"], dtype=float), np.array(m["vb"], dtype=float)
    fa, fb = np.array(m["fa"]), np.array(m["fb"])
    na = len(va)
    vt, gt, nt = potential(np.vstack([va, vb]), np.vstack([fa, fb + na]), m["dhat"])
    v1, g1, n1 = potential(va, fa, m["dhat"])
    v2, g2, n2 = potential(vb, fb, m["dhat"])
    g = gt - np.concatenate([g1, g2])
    return {"value": vt - v1 - v2, "grad": list(g), "collisions": nt - n1 - n2}


def friction(v, f, du, m):
    v = np.asfortranarray(v)
    f = np.asarray(f, dtype=np.int32)
    mesh = ipctk.CollisionMesh(v, np.asfortranarray(edges_of(f)), np.asfortranarray(f))
    col = ipctk.NormalCollisions()
    col.build(mesh, v, m["dhat"])
    tc = ipctk.TangentialCollisions()
    tc.build(mesh, v, col, ipctk.BarrierPotential(m["dhat"], m["kappa"]), m["mu"])
    pot = ipctk.FrictionPotential(m["eps"])
    du = np.asfortranarray(du)
    return pot(tc, mesh, du), np.asarray(pot.gradient(tc, mesh, du)), len(tc)


def friction_pair(m):
    # As mesh_pair: the combined meshes' friction minus each mesh's own.
    va, vb = np.array(m["va"], dtype=float), np.array(m["vb"], dtype=float)
    fa, fb = np.array(m["fa"]), np.array(m["fb"])
    ua, ub = np.array(m["ua"], dtype=float), np.array(m["ub"], dtype=float)
    na = len(va)
    vt, gt, nt = friction(np.vstack([va, vb]), np.vstack([fa, fb + na]), np.vstack([ua, ub]), m)
    v1, g1, n1 = friction(va, fa, ua, m)
    v2, g2, n2 = friction(vb, fb, ub, m)
    g = gt - np.concatenate([g1, g2])
    return {"value": vt - v1 - v2, "grad": list(g), "collisions": nt - n1 - n2}


def ccd(c, tool):
    a = [np.array(v, dtype=float) for v in c["x0"]]
    b = [np.array(v, dtype=float) for v in c["x1"]]
    if c["kind"] == "pt":
        hit, toi = tool.point_triangle_ccd(*a, *b, min_distance=0.0, tmax=1.0)
    else:
        hit, toi = tool.edge_edge_ccd(*a, *b, min_distance=0.0, tmax=1.0)
    toi = float(toi)
    return {"hit": bool(hit), "toi": toi if np.isfinite(toi) else None}


def main():
    job = json.load(sys.stdin)
    tool = ipctk.TightInclusionCCD()
    out = {
        "version": ipctk.__version__ if hasattr(ipctk, "__version__") else "?",
        "primitives": [primitive(p) for p in job.get("primitives", [])],
        "meshes": [mesh_pair(m) for m in job.get("meshes", [])],
        "ccd": [ccd(c, tool) for c in job.get("ccd", [])],
        "friction_meshes": [friction_pair(m) for m in job.get("friction_meshes", [])],
        "friction": [
            {"f0": ipctk.smooth_friction_f0(y, e), "f1": ipctk.smooth_friction_f1(y, e)}
            for y, e in job.get("friction", [])
        ],
    }
    # ipctk may log to stdout: the result goes to the file named on the
    # command line when one is given.
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w") as f:
            json.dump(out, f, allow_nan=False)
    else:
        json.dump(out, sys.stdout, allow_nan=False)


if __name__ == "__main__":
    main()
