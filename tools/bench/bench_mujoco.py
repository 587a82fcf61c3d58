#!/usr/bin/env python3
"""MuJoCo side of the four-chain benchmark (`tools/bench/bench_vs_mujoco.sh`).

    python tools/bench/bench_mujoco.py [--scene robots/four_chains.yaml] --links N \
        [--steps 600] [--json out.json] [--mjcf model.xml]
    python tools/bench/bench_mujoco.py summarize ROWS.jsonl

The model is built from the SDRS scene (every robot with a `chain`):

- each link a box `w × w × l` hanging along −z from its joint, the next link
  attached at its far end (src/scene/chain.rs);
- SDRS's default mass model lumps a link's mass equally on its hull's
  vertices (the 8 box corners), so each MuJoCo body gets mass `m`, centre
  of mass `(0, 0, −l/2)` and the corners' inertia about it,
  `I_xx = I_yy = m((w/2)² + (l/2)²)`, `I_zz = 2m(w/2)²`;
- each `ball` joint (SDRS: two hinges about x then y) is two MuJoCo hinges
  about x and y at the same point;
- SDRS's PD term `k_p e² + k_d ė²` in the step objective is the torque
  `2k_p(θ* − θ) + (2k_d/Δt)(θ̇* − θ̇)`; MuJoCo gets a `position` actuator
  with `kp = 2k_p`, `kv = 2k_d/Δt` (so the damping is integrated
  implicitly) and `ctrl = θ* + (kv/kp) θ̇*` (then `kp(ctrl − θ) − kv θ̇`
  is exactly the SDRS torque);
- contact between every pair of links except parent–child (MuJoCo's
  default filter), friction `μ` from the scene's `contact`;
- `timestep = dt` (0.005 s), integrator `implicit`, gravity as in the scene.

Timed: the `mj_step` calls only (the controller's targets are set outside
the timer), over `--steps` steps. The JSON gives ms/step, MuJoCo's own
per-stage timers (`data.timer`), and each body's mass, centre of mass and
inertia (the CI smoke test compares them with the SDRS model).

`summarize` reads JSON lines `{"engine": "sdrs"|"mujoco", ...}` (as written
by `tools/bench/bench_vs_mujoco.sh`) and prints ratio per N, growth exponents
(least-squares slope of log cost vs log N over N = 8…32) and the SDRS
stage shares.
"""
import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def chain_mjcf(scene, links):
    """MJCF text of the scene's chains with `links` links each; returns
    (xml, list of actuated (robot, joint, [signal, signal]) targets)."""
    dt = float(scene.get("dt", 0.005))
    g = scene.get("gravity", [0.0, 0.0, -9.81])
    mu = float((scene.get("contact") or {}).get("mu", 0.2))
    out = [
        '<mujoco model="four_chains">',
        f'  <option timestep="{dt!r}" integrator="implicit" gravity="{g[0]!r} {g[1]!r} {g[2]!r}"/>',
        f'  <default><geom friction="{mu!r} 0.005 0.0001" density="0"/></default>',
        "  <worldbody>",
    ]
    acts = []
    targets = []
    for r in scene["robots"]:
        c = r.get("chain")
        if c is None:
            continue
        name = r["name"]
        base = (r.get("base") or {}).get("xyz", [0.0, 0.0, 0.0])
        l = float(c.get("link_length", 0.5))
        w = float(c.get("link_width", 0.1))
        m = float(c.get("link_mass", 0.1))
        joint = c.get("joint", "ball")
        ixx = m * ((w / 2) ** 2 + (l / 2) ** 2)
        izz = 2 * m * (w / 2) ** 2
        ctrl = r.get("controller") or {}
        kp, kd = float(ctrl.get("kp", 0.0)), float(ctrl.get("kd", 0.0))
        depth = 0
        for i in range(links):
            pos = f"{base[0]!r} {base[1]!r} {base[2]!r}" if i == 0 else f"0 0 {-l!r}"
            out.append("    " + "  " * depth + f'<body name="{name}_link{i}" pos="{pos}">')
            ind = "    " + "  " * (depth + 1)
            hinges = [("x", "1 0 0"), ("y", "0 1 0")] if joint == "ball" else [("y", "0 1 0")]
            for ax, vec in hinges:
                out.append(f'{ind}<joint name="{name}_j{i}_{ax}" type="hinge" axis="{vec}" pos="0 0 0"/>')
            out.append(
                f'{ind}<inertial pos="0 0 {-l / 2!r}" mass="{m!r}" diaginertia="{ixx!r} {ixx!r} {izz!r}"/>'
            )
            out.append(
                f'{ind}<geom name="{name}_geom{i}" type="box" size="{w / 2!r} {w / 2!r} {l / 2!r}" pos="0 0 {-l / 2!r}"/>'
            )
            sigs = (ctrl.get("targets") or {}).get(f"j{i}")
            if sigs is not None and kp > 0:
                if isinstance(sigs, dict):
                    sigs = [sigs]
                for (ax, _), sig in zip(hinges, sigs):
                    jn = f"{name}_j{i}_{ax}"
                    kpm, kvm = 2 * kp, 2 * kd / dt
                    acts.append(f'    <position joint="{jn}" kp="{kpm!r}" kv="{kvm!r}" ctrllimited="false"/>')
                    targets.append((sig, kvm / kpm))
            depth += 1
        for d in range(depth, 0, -1):
            out.append("    " + "  " * (d - 1) + "</body>")
    out.append("  </worldbody>")
    out.append("  <actuator>")
    out.extend(acts)
    out.append("  </actuator>")
    out.append("</mujoco>")
    return "\n".join(out) + "\n", targets


def run(a):
    import mujoco
    import numpy as np
    import yaml

    sys.path.insert(0, os.path.join(HERE, "..", "check"))
    from scene_signals import signal

    with open(a.scene) as f:
        scene = yaml.safe_load(f)
    xml, targets = chain_mjcf(scene, a.links)
    if a.mjcf:
        with open(a.mjcf, "w") as f:
            f.write(xml)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    t0 = time.perf_counter
    best = None
    # The same trajectory `--repeats` times from the initial state; the
    # fastest run's time is reported (robust to interruptions).
    for _ in range(max(1, a.repeats)):
        mujoco.mj_resetData(model, data)
        contacts = 0
        step_s = 0.0
        for k in range(a.steps):
            t = k * dt
            for j, (sig, lead) in enumerate(targets):
                v, d = signal(sig, t)
                data.ctrl[j] = v + lead * d
            s = t0()
            mujoco.mj_step(model, data)
            step_s += t0() - s
            contacts += data.ncon
        best = step_s if best is None else min(best, step_s)
    step_s = best
    bodies = []
    for b in range(1, model.nbody):
        bodies.append(
            {
                "name": mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b),
                "mass": float(model.body_mass[b]),
                "com": [float(x) for x in model.body_ipos[b]],
                "inertia": [float(x) for x in model.body_inertia[b]],
            }
        )
    timers = {}
    for name in ("step", "forward", "position", "velocity", "acceleration", "constraint",
                 "pos_kinematics", "pos_inertia", "pos_collision", "pos_make",
                 "pos_project", "posvel", "actuation", "advance"):
        idx = getattr(mujoco.mjtTimer, f"mjTIMER_{name.upper()}", None)
        if idx is not None:
            timers[name] = float(data.timer[int(idx)].duration)
    row = {
        "engine": "mujoco",
        "version": mujoco.__version__,
        "links_per_chain": a.links,
        "dof": int(model.nv),
        "steps": a.steps,
        "repeats": max(1, a.repeats),
        "ms_per_step": 1e3 * step_s / a.steps,
        "mean_contacts": contacts / a.steps,
        "timers_ms_total": {k: 1e3 * v for k, v in timers.items()},
        "bodies": bodies,
        "final_qpos_abs_max": float(np.abs(data.qpos).max()),
    }
    text = json.dumps(row)
    if a.json:
        with open(a.json, "w") as f:
            f.write(text + "\n")
    print(f"mujoco N={a.links} dof={model.nv} {row['ms_per_step']:.4f} ms/step, "
          f"{row['mean_contacts']:.1f} contacts/step")


def slope(xs, ys):
    """Least-squares slope of log y against log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    num = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    den = sum((a - mx) ** 2 for a in lx)
    return num / den


def summarize(path):
    rows = [json.loads(l) for l in open(path) if l.strip()]
    by = {}
    for r in rows:
        by.setdefault(r["links_per_chain"], {}).setdefault(r["engine"], []).append(r)
    ns = sorted(by)
    print("| links/chain | dof | sdrs ms/step | MuJoCo ms/step | ratio | ratio per round (min–max) | Newton it/step | linear_solve % | contact % | broad phase % |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    med = lambda v: sorted(v)[len(v) // 2]
    table = []
    for n in ns:
        s, m = by[n].get("sdrs", []), by[n].get("mujoco", [])
        if not s or not m:
            continue
        sm = med([r["ms_per_step"] for r in s])
        mm = med([r["ms_per_step"] for r in m])
        r0 = s[0]
        share = lambda name: med([_share(r, name) for r in s])
        table.append((n, sm, mm))
        # Each round ran the two engines back to back: its own ratio shows how
        # much the machine moved between rounds.
        per_round = [a["ms_per_step"] / b["ms_per_step"] for a, b in zip(s, m)]
        print(f"| {n} | {r0['dof']} | {sm:.3f} | {mm:.4f} | {sm / mm:.2f} | "
              f"{min(per_round):.2f}–{max(per_round):.2f} | "
              f"{r0['newton_iterations_per_step']:.2f} | {share('linear_solve'):.1f} | "
              f"{share('contact'):.1f} | {share('broad_phase'):.1f} |")
    big = [t for t in table if t[0] >= 8]
    if len(big) >= 2:
        xs = [t[0] for t in big]
        print(f"\ngrowth over N = {xs[0]}..{xs[-1]}: sdrs N^{slope(xs, [t[1] for t in big]):.2f}, "
              f"MuJoCo N^{slope(xs, [t[2] for t in big]):.2f}")
    if table:
        worst = max(table, key=lambda t: t[1] / t[2])
        print(f"worst ratio {worst[1] / worst[2]:.2f} at N = {worst[0]}")
    if table:
        # Stage shares: the median over rounds of each round's share (the
        # table's columns too); the linear solve's range over rounds beside it.
        n, _, _ = table[-1]
        s = by[n]["sdrs"]
        names = sorted({st["stage"] for r in s for st in r["stages"]})
        parts = sorted(((med([_share(r, name) for r in s]), name) for name in names), reverse=True)
        print(f"\nsdrs stage shares at N = {n} (median of {len(s)} rounds): " + ", ".join(
            f"{name} {v:.1f}%" for v, name in parts))
        ls = [_share(r, "linear_solve") for r in s]
        print(f"linear_solve share at N = {n} over the rounds: {min(ls):.1f}–{max(ls):.1f}%")


def _share(row, name):
    """Percentage of one run's timed stages spent in stage `name`."""
    total = sum(st["seconds"] for st in row["stages"]) or 1.0
    return 100.0 * sum(st["seconds"] for st in row["stages"] if st["stage"] == name) / total


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "summarize":
        if len(sys.argv) != 3:
            print("usage: bench_mujoco.py summarize ROWS.jsonl", file=sys.stderr)
            sys.exit(2)
        summarize(sys.argv[2])
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=os.path.join(ROOT, "robots", "four_chains.yaml"))
    ap.add_argument("--links", type=int, required=True)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--repeats", type=int, default=1,
                    help="timed runs of the trajectory; the fastest is reported")
    ap.add_argument("--json")
    ap.add_argument("--mjcf", help="also write the MJCF model here")
    a = ap.parse_args()
    if a.links < 1 or a.steps < 1:
        print("--links and --steps must be at least 1", file=sys.stderr)
        sys.exit(2)
    run(a)


if __name__ == "__main__":
    main()
