#!/usr/bin/env python3
"""Timing of one barrier-potential evaluation (value + gradient + Hessian,
vertex space, collision set built from scratch) with ipc-toolkit on the hull
pairs written by `cargo run --release -p sdrs-ipc --example bench_potential
CASES.json`, for the side-by-side table of the README.

Usage: bench_ipctk.py CASES.json [--reps N]
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
    a = ap.parse_args()
    by_size = {}
    for c in json.load(open(a.cases)):
        va, vb = np.array(c["va"]), np.array(c["vb"])
        na = len(va)
        v = np.asfortranarray(np.vstack([va, vb]))
        f = np.vstack([np.array(c["fa"]), np.array(c["fb"]) + na]).astype(np.int32)
        mesh = ipctk.CollisionMesh(v, np.asfortranarray(edges_of(f)), np.asfortranarray(f))
        mesh.can_collide = lambda i, j, na=na: (i < na) != (j < na)
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
    print("vertices | ipctk µs (median of cases; includes the collision build)")
    for n in sorted(by_size):
        print(f"{n:>8} | {np.median(by_size[n]):10.1f}")


if __name__ == "__main__":
    main()
