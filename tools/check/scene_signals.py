"""Shared by the MuJoCo cross-check scripts: scene target signals and URDF
roll-pitch-yaw rotations, as `sdrs` defines them (src/control/signal.rs,
src/math)."""
import math

import numpy as np


def signal(sig, t):
    """Value and time derivative of a scene target signal at time t (s);
    `constant` and `sine` only (ValueError otherwise)."""
    kind = sig["type"]
    if kind == "constant":
        return sig["value"], 0.0
    if kind == "sine":
        v, d = sig.get("offset", 0.0), 0.0
        for term in sig["terms"]:
            w = 2 * math.pi * term["frequency"]
            ph = term.get("phase", 0.0)
            v += term["amplitude"] * math.sin(w * t + ph)
            d += term["amplitude"] * w * math.cos(w * t + ph)
        return v, d
    raise ValueError(f"unsupported target signal type {kind!r} (sine and constant only)")


def rpy_matrix(r, p, y):
    """R = Rz(y) Ry(p) Rx(r) (URDF's fixed-axis roll, pitch, yaw)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx
