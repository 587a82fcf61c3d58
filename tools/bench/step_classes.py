#!/usr/bin/env python3
"""Per-step time of SDRS and MuJoCo on the four chains, split by contact.

    step_classes.py mujoco --links N --steps S --rounds R --out mj.csv
    step_classes.py chains --links N --out scene.yaml
    step_classes.py summarize DIR N [N ...]

`mujoco`: MuJoCo's `mj_step` on the chains of `bench_mujoco.py` (same MJCF,
same controller targets), each step's minimum wall time over R runs of the
same deterministic trajectory, with `ncon`, as CSV `step,seconds,ncon`.
`chains`: `robots/four_chains.yaml` with `chain.links = N` (as `sdrs bench`
sets it). `summarize`: reads `DIR/sdrs<N>.csv` (`examples/step_classes.rs`)
and `DIR/mj<N>.csv` and prints, per N, both engines' time per step, their
ratio, and each engine's steps with and without contact (SDRS: an active
pair; MuJoCo: `ncon > 0`). Driven by `tools/bench/step_classes.sh`.
"""
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCENE = os.path.join(ROOT, "robots", "four_chains.yaml")


def arg(name, default=None):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    if default is None:
        sys.exit(f"step_classes.py: {name} is required")
    return default


def chains(links, out):
    import yaml

    with open(SCENE) as f:
        spec = yaml.safe_load(f)
    for r in spec.get("robots", []):
        if "chain" in r:
            r["chain"]["links"] = links
    with open(out, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False)


def mujoco_steps(links, steps, rounds, out):
    import mujoco
    import yaml

    sys.path.insert(0, HERE)
    sys.path.insert(0, os.path.join(ROOT, "tools", "check"))
    import bench_mujoco
    from scene_signals import signal

    with open(SCENE) as f:
        scene = yaml.safe_load(f)
    xml, targets = bench_mujoco.chain_mjcf(scene, links)
    model = mujoco.MjModel.from_xml_string(xml)
    best, ncon = [float("inf")] * steps, [0] * steps
    for _ in range(rounds):
        data = mujoco.MjData(model)
        for k in range(steps):
            t = k * model.opt.timestep
            for j, (sig, lead) in enumerate(targets):
                v, d = signal(sig, t)
                data.ctrl[j] = v + lead * d
            s = time.perf_counter()
            mujoco.mj_step(model, data)
            best[k] = min(best[k], time.perf_counter() - s)
            ncon[k] = data.ncon
    with open(out, "w") as f:
        f.write("step,seconds,ncon\n")
        for k in range(steps):
            f.write(f"{k},{best[k]:.9f},{ncon[k]}\n")


def load(path, flag):
    rows = list(csv.DictReader(open(path)))
    return [float(r["seconds"]) * 1e3 for r in rows], [int(r[flag]) > 0 for r in rows], rows


def mean(v):
    return sum(v) / len(v) if v else float("nan")


def summarize(folder, ns):
    print("| links/chain | sdrs ms/step | MuJoCo ms/step | ratio | steps in contact sdrs / MuJoCo "
          "| sdrs ms per contact / free step | MuJoCo ms per contact / free step "
          "| ratio on steps free in both | sdrs time in contact steps | of it, steps with ≥ 3 Newton iterations |")
    print("|---:|---:|---:|---:|---|---|---|---:|---:|---:|")
    for n in ns:
        s, sc, rows = load(os.path.join(folder, f"sdrs{n}.csv"), "pairs")
        m, mc, _ = load(os.path.join(folder, f"mj{n}.csv"), "ncon")
        it = [int(r["iters"]) for r in rows]
        steps = len(s)
        pick = lambda v, mask: [x for x, c in zip(v, mask) if c]
        free_both = [not a and not b for a, b in zip(sc, mc)]
        tail = sum(x for x, c, i in zip(s, sc, it) if c and i >= 3)
        in_contact = sum(pick(s, sc))
        print(f"| {n} | {sum(s) / steps:.4f} | {sum(m) / steps:.4f} | {sum(s) / sum(m):.2f} "
              f"| {sum(sc)} / {sum(mc)} "
              f"| {mean(pick(s, sc)):.4f} / {mean(pick(s, [not c for c in sc])):.4f} "
              f"| {mean(pick(m, mc)):.4f} / {mean(pick(m, [not c for c in mc])):.4f} "
              f"| {sum(pick(s, free_both)) / max(sum(pick(m, free_both)), 1e-300):.2f} "
              f"| {100 * in_contact / sum(s):.0f} % | {100 * tail / sum(s):.0f} % |")


def main():
    if len(sys.argv) < 2 or sys.argv[1] not in ("mujoco", "chains", "summarize"):
        sys.exit(__doc__)
    if sys.argv[1] == "summarize":
        if len(sys.argv) < 4:
            sys.exit("usage: step_classes.py summarize DIR N [N ...]")
        summarize(sys.argv[2], [int(n) for n in sys.argv[3:]])
        return
    links = int(arg("--links"))
    if sys.argv[1] == "chains":
        chains(links, arg("--out"))
    else:
        mujoco_steps(links, int(arg("--steps", "600")), int(arg("--rounds", "7")), arg("--out"))


if __name__ == "__main__":
    main()
