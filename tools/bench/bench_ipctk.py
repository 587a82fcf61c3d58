#!/usr/bin/env python3
"""Timing of one barrier-potential evaluation (value + gradient + Hessian,
vertex space, collision set built from scratch) with ipc-toolkit on the hull
pairs written by `cargo run --release -p sdrs-cli --example bench_potential
CASES.json`, for the side-by-side table of the README.

The two hulls are one ipctk CollisionMesh without a per-pair filter: a
Python `can_collide` callback dominates the timing (and a TBB worker calling
back into Python deadlocked once), so ipctk's figure also includes each
hull's own near-primitive pairs, which its broad phase must visit. It is an
upper bound on ipctk's inter-hull cost.

Usage: bench_ipctk.py CASES.json [--reps N] [--json]
"""
import argparse
import json
import time

import numpy as np
import ipctk


def edges_of(faces):
    e = set()
    for f in faces:
        for k in range(3):
            a, b = int(f[k]), int(f[(k + 1) % 3])
            e.add((min(a, b), max(a, b)))
    return np.array(sorted(e), dtype=np.int32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases")
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--json", action="store_true", help="print {vertices: µs} as JSON")
    a = ap.parse_args()
    by_size = {}
    for c in json.load(open(a.cases)):
        va, vb = np.array(c["va"]), np.array(c["vb"])
        na = len(va)
        v = np.asfortranarray(np.vstack([va, vb]))
        f = np.vstack([np.array(c["fa"]), np.array(c["fb"]) + na]).astype(np.int32)
        mesh = ipctk.CollisionMesh(v, np.asfortranarray(edges_of(f)), np.asfortranarray(f))
        pot = ipctk.BarrierPotential(c["dhat"], 1.0)

        def once():
            col = ipctk.NormalCollisions()
            col.build(mesh, v, c["dhat"])
            pot(col, mesh, v)
            pot.gradient(col, mesh, v)
            pot.hessian(col, mesh, v)

        once()
        t = []
        for _ in range(a.reps):
            s = time.perf_counter()
            once()
            t.append((time.perf_counter() - s) * 1e6)
        by_size.setdefault(c["vertices"], []).append(float(np.median(t)))
    if a.json:
        print(json.dumps({str(n): float(np.median(by_size[n])) for n in sorted(by_size)}))
        return
    print("vertices | ipctk µs (median of cases; includes the collision build)")
    for n in sorted(by_size):
        print(f"{n:>8} | {np.median(by_size[n]):10.1f}")


if __name__ == "__main__":
    main()
