#!/usr/bin/env python3
"""Independent check of a `.glb` written by `sdrs view --format glb`.

Loads the file with trimesh (its glTF importer: meshes, node graph) and
reads the glTF JSON and binary chunks directly for what trimesh ignores
(animations). Checks: the binary container (magic, version, lengths,
4-byte aligned chunks), every accessor's byte range inside its buffer
view, the animation's input times (non-decreasing, min/max as declared),
every channel's output count equal to the input count, unit quaternions,
and, with --poses, the last keyframe's translations equal to the last
recorded link positions of `poses.csv` (f32 precision).

Prints a JSON summary: nodes, link nodes (children of the root), meshes
and triangles seen by trimesh, animation duration (s), keyframes.
Usage: check_glb.py FILE.glb [--poses DIR/poses.csv]
"""
import argparse
import json
import struct
import sys

import numpy as np
import trimesh

COMPONENTS = {5126: np.float32, 5125: np.uint32}
WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}


def fail(msg):
    print(f"check_glb: {msg}", file=sys.stderr)
    sys.exit(1)


def read(path):
    b = open(path, "rb").read()
    magic, version, total = struct.unpack_from("<4sII", b, 0)
    if magic != b"glTF" or version != 2 or total != len(b):
        fail(f"bad header: {magic} v{version} length {total} of {len(b)}")
    jl, jt = struct.unpack_from("<I4s", b, 12)
    if jt != b"JSON" or jl % 4:
        fail("bad JSON chunk")
    doc = json.loads(b[20:20 + jl])
    bl, bt = struct.unpack_from("<I4s", b, 20 + jl)
    if bt != b"BIN\0" or bl % 4:
        fail("bad BIN chunk")
    return doc, b[28 + jl:28 + jl + bl]


def accessor(doc, bin_, i):
    a = doc["accessors"][i]
    v = doc["bufferViews"][a["bufferView"]]
    n = a["count"] * WIDTH[a["type"]]
    dt = COMPONENTS[a["componentType"]]
    start = v.get("byteOffset", 0) + a.get("byteOffset", 0)
    if start % 4 or start + n * 4 > v.get("byteOffset", 0) + v["byteLength"]:
        fail(f"accessor {i} outside its buffer view")
    x = np.frombuffer(bin_, dtype=dt, count=n, offset=start).reshape(a["count"], -1)
    for key, f in (("min", np.min), ("max", np.max)):
        if key in a and not np.allclose(a[key], f(x, axis=0), rtol=0, atol=1e-6):
            fail(f"accessor {i}: {key} {a[key]} differs from the data {f(x, axis=0)}")
    return x


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("glb")
    ap.add_argument("--poses")
    args = ap.parse_args()
    doc, bin_ = read(args.glb)
    scene = trimesh.load(args.glb, force="scene")
    root = doc["nodes"][doc["scenes"][doc.get("scene", 0)]["nodes"][0]]
    links = root.get("children", [])
    out = {
        "nodes": len(doc["nodes"]),
        "link_nodes": len(links),
        "trimesh_geometries": len(scene.geometry),
        "trimesh_triangles": int(sum(len(g.faces) for g in scene.geometry.values())),
        "trimesh_graph_nodes": len(scene.graph.nodes_geometry),
    }
    anims = doc.get("animations", [])
    if len(anims) != 1:
        fail(f"{len(anims)} animations, expected 1")
    an = anims[0]
    inputs = {s["input"] for s in an["samplers"]}
    if len(inputs) != 1:
        fail("samplers do not share one time input")
    t = accessor(doc, bin_, inputs.pop())[:, 0]
    if np.any(np.diff(t) < 0):
        fail("keyframe times decrease")
    last_t = {}
    for ch in an["channels"]:
        s = an["samplers"][ch["sampler"]]
        y = accessor(doc, bin_, s["output"])
        if len(y) != len(t):
            fail(f"channel of node {ch['target']['node']}: {len(y)} values for {len(t)} times")
        if ch["target"]["path"] == "rotation":
            norms = np.linalg.norm(y, axis=1)
            if np.max(np.abs(norms - 1)) > 1e-5:
                fail(f"node {ch['target']['node']}: non-unit quaternion")
        else:
            last_t[ch["target"]["node"]] = y[-1]
    animated = {ch["target"]["node"] for ch in an["channels"]}
    if animated != set(links):
        fail(f"animated nodes {sorted(animated)} are not the link nodes {links}")
    if args.poses:
        rows = np.loadtxt(args.poses, delimiter=",", skiprows=1, usecols=(0, 2, 13, 14, 15))
        last = rows[rows[:, 0] == rows[:, 0].max()]
        for r in last:
            node = links[int(r[1])]
            if not np.allclose(last_t[node], r[2:], rtol=0, atol=1e-5):
                fail(f"link {int(r[1])}: last translation {last_t[node]} vs poses.csv {r[2:]}")
        out["checked_against_poses"] = len(last)
    out["duration"] = float(t[-1] - t[0])
    out["keyframes"] = len(t)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
