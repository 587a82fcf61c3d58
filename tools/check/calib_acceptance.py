"""Calibration acceptance on robots nobody here wrote (issue 33, item 3).

For each third-party MJCF model (gymnasium's bundled models by default):

1. `sdrs import MODEL.xml` makes the scene a user would start from; the
   script only replaces the controller targets by a sine excitation per
   joint, sets the step, the duration and turns contact off (contact-free
   cases), and writes it as `<case>/scene.yaml`.
2. MuJoCo simulates the *original* MJCF (its own integrator, default RK4 at
   1e-4 s, contact disabled) under the scene's stable-PD law in SDRS's
   convention, τ = 2k_p(θ* − θ) + (2k_d/Δt_sdrs)(θ̇* − θ̇), applied as a
   generalized force, with hidden effects switched on in the MJCF model:
   joint damping (`dof_damping`), dry friction (`dof_frictionloss`),
   armature (`dof_armature`) and a point payload on a body (its mass,
   centre of mass and inertia updated by the parallel-axis rule).
3. Samples at 100 Hz with Gaussian noise (1e-3), `sdrs calibrate` on the
   imported scene, and the verdict compared with the truth:
   clean → `none`; one effect → that effect alone, within 10 %;
   two → both, each within 15 %; an effect outside the library (an
   actuation delay, a velocity-squared drag; `cases_for`) → `unexplained`
   or the new effect, never a wrong library effect, with the residual
   regression naming the joint and term.

    python tools/check/calib_acceptance.py --sdrs target/release/sdrs --out out/acc \
        [--cases quick|all] [--robots reacher,inverted_double_pendulum]

Several recordings, one model (issue 33, item 4): `--initial J=V,…` starts
the MuJoCo data (and the case's scene) at another state of the measured
joints; with `--two-recordings` recording A starts from the model's state
and B from `--initial`, and each case is calibrated on A alone, B alone
(the scene started at B's state) and A + B (`--measured` twice; B is then
simulated from its first sample, as `sdrs calibrate` starts any further
recording). Each fit must meet the case's rule, and the joint fit lie
inside both single fits' 95 % intervals:

    python tools/check/calib_acceptance.py --sdrs target/release/sdrs --out out/two \
        --robots reacher --only damping_all --initial joint0=-0.5,joint1=0.5 --two-recordings

Prints one line per case and writes `<out>/summary.json`. Exit status 1 if
a target is missed (the table says which). `--cases quick` (CI size) runs
the clean and one-effect damping cases of the first robot.
"""

import argparse
import copy
import json
import os
import subprocess
import sys

import mujoco
import numpy as np
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scene_signals import signal  # noqa: E402

ASSETS = os.path.join(os.path.dirname(mujoco.__file__), "..", "gymnasium", "envs", "mujoco", "assets")

# Robot: joints to excite (sine amplitude rad or m, frequency Hz[, offset rad
# or m, also the joint's initial coordinate in both engines]), the SDRS
# step, and hidden effects per case: (sdrs key, true value, mujoco setter).
ROBOTS = {
    # Planar arm; the MJCF's own damping 1 and armature 1 per joint come in
    # through the import. Hidden values are fractions of those (a damping
    # and an armature scaled by the same factor would be one actuator gain).
    "reacher": {
        "file": "reacher.xml",
        "excite": {"joint0": (0.8, 0.7), "joint1": (0.7, 1.1)},
        "dt": 1e-3,
        "gain_scale": 1.0,
        "hidden": {"damping": 0.5, "friction": 0.3, "armature": 0.3, "delay": 0.02, "drag": 1.0},
        # Armature + damping is degenerate here (see `cases_for`).
        "pair": ("damping", "friction"),
    },
    # Cart and two poles upright. The imported PD gains (from the motors'
    # gear) make a damping of 0.5 invisible (the PD's own damping is
    # 2k_d/Δt ≈ 290 N·m·s/rad): the gains are scaled by 0.05 (still
    # holding the poles up) and the hidden values sized to them.
    "inverted_double_pendulum": {
        "file": "inverted_double_pendulum.xml",
        "excite": {"slider": (0.2, 0.6), "hinge": (0.3, 0.9), "hinge2": (0.3, 1.3)},
        "dt": 1e-3,
        "gain_scale": 0.05,
        "hidden": {"damping": 5.0, "friction": 5.0, "armature": 0.5, "delay": 0.02, "drag": 2.0},
        "pair": ("damping", "armature"),
    },
    # 7-DOF arm nobody here tuned on (session 19, registered before any
    # calibration). All seven arm joints are excited (a hidden effect on
    # `all` is added to the excited joints only, and SDRS's `all` covers
    # every joint); the object's and goal's slide joints are left alone:
    # separate roots, no force, no contact, no gravity, at rest in both
    # engines. The elbow and wrist flex ranges end at 0 (the import drops
    # those limits, MuJoCo keeps them): excited about offsets inside them.
    # Imported gains kept (PD damping 0.6–2.8 N·m·s/rad does not hide a
    # damping of 0.1: signature 2.8e-2 RMS with MuJoCo alone). Pair
    # damping + armature: the links' inertia (≈ 1 kg·m² at the shoulder,
    # ≤ 2e-3 at the wrist) against the armature 0.04 breaks the reacher's
    # gain degeneracy.
    "pusher": {
        "file": "pusher.xml",
        "excite": {"r_shoulder_pan_joint": (0.5, 0.61), "r_shoulder_lift_joint": (0.3, 0.83, 0.3),
                   "r_upper_arm_roll_joint": (0.5, 0.97), "r_elbow_flex_joint": (0.5, 1.13, -1.1),
                   "r_forearm_roll_joint": (0.5, 1.31), "r_wrist_flex_joint": (0.3, 1.49, -0.55),
                   "r_wrist_roll_joint": (0.5, 1.73)},
        "dt": 1e-3,
        "gain_scale": 1.0,
        "hidden": {"damping": 0.1, "friction": 0.5, "armature": 0.01, "delay": 0.02, "drag": 0.03},
        "pair": ("damping", "armature"),
    },
}


def cases_for(spec):
    """(name, hidden effects, expected structure outside the library or None).

    Hidden effects are (sdrs key, true value, (mujoco setting, joint or None
    for all)). The two-effect case is the robot's `pair`: on the reacher the
    MJCF's armature 1 per joint dominates the links' inertia (1e-3), so an
    added armature a with a damping c is, to 0.1 %, an actuator gain
    1/(1 + a) with a damping (1 + c)/(1 + a) − 1 (measured: a = 0.3, c = 0.5
    fitted as gain 0.767, damping 0.128; predicted 0.769, 0.154): the
    question has no answer from these data, and the reacher's pair is
    damping + dry friction instead (issue 33 session 3).

    Effects outside the library: an actuation delay on the first joint (the
    library's new `actuation_delay`, or `unexplained` with the residual
    regression naming the joint's `u̇`) and a velocity-squared drag
    τ = −c₂ θ̇|θ̇| on the last joint (`unexplained`, the regression naming
    `θ̇|θ̇|` on that joint). The reacher's drag was first 0.1 (chosen to
    match the damping case's torque); its gap came out 2.9e-3, 2.5× the
    noise and about the model's own floor, too small to test the rule, and
    it is now 1.0.
    """
    joints = list(spec["excite"])
    j0, jl = joints[0], joints[-1]
    h = spec["hidden"]
    one = {
        "damping": ("joint_damping/all", h["damping"], ("damping", None)),
        "armature": ("armature/all", h["armature"], ("armature", None)),
        "friction": ("joint_friction/" + j0, h["friction"], ("frictionloss", j0)),
    }
    a, b = spec["pair"]
    return [
        ("clean", [], None),
        ("damping_all", [one["damping"]], None),
        ("friction_" + j0, [one["friction"]], None),
        ("armature_all", [one["armature"]], None),
        (f"{a}+{b}", [one[a], one[b]], None),
        ("delay_" + j0, [("actuation_delay/" + j0, h["delay"], ("delay", j0))], (j0, "u̇")),
        ("drag_" + jl, [("drag/" + jl, h["drag"], ("drag", jl))], (jl, "θ̇|θ̇|")),
    ]


def fail(msg):
    print(f"calib_acceptance: {msg}", file=sys.stderr)
    sys.exit(2)


def make_scene(args, robot, spec, case_dir, initial=None, name="scene.yaml"):
    src = os.path.join(ASSETS, spec["file"])
    raw = os.path.join(case_dir, "imported.yaml")
    r = subprocess.run([args.sdrs, "import", src, "--out", raw, "--decomposer", "hull", "--force"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"sdrs import {src}: {r.stderr.strip()}")
    with open(raw) as f:
        sc = yaml.safe_load(f)
    # PyYAML reads the key `on:` as the boolean true (YAML 1.1).
    for e in sc.get("effects", []):
        if True in e:
            e["on"] = e.pop(True)
    sc["dt"] = spec["dt"]
    sc["steps"] = int(round(args.duration / spec["dt"]))
    for key in ("contact", "ground", "obstacles"):
        sc.pop(key, None)
    rob = sc["robots"][0]
    ctrl = rob["controller"]
    targets = {}
    for j, (amp, freq, *off) in spec["excite"].items():
        targets[j] = {"type": "sine", "terms": [{"amplitude": amp, "frequency": freq}]}
        if off:
            # A joint whose range excludes 0 is excited about an offset inside
            # it, and both engines start there (the target's value at t = 0).
            targets[j]["offset"] = off[0]
            rob.setdefault("initial", {})[j] = {"q": [off[0]], "qdot": [0.0]}
    ctrl["targets"] = targets
    for g in ctrl.get("gains", {}).values():
        g["kp"] *= spec["gain_scale"]
        g["kd"] *= spec["gain_scale"]
    ctrl["kp"] = ctrl.get("kp", 0.0) * spec["gain_scale"]
    ctrl["kd"] = ctrl.get("kd", 0.0) * spec["gain_scale"]
    if initial:
        init = rob.setdefault("initial", {})
        for j, q in initial.items():
            init[j] = {"q": [q], "qdot": [0.0]}
    path = os.path.join(case_dir, name)
    with open(path, "w") as f:
        yaml.safe_dump(sc, f, sort_keys=False)
    return path, sc


def simulate_mujoco(args, spec, sc, hidden, out_csv, seed, initial=None):
    """MuJoCo data for one case. `initial` ({joint: q}, the `--initial`
    state) replaces the scene's initial coordinate of those joints; every
    velocity starts at 0, as `sdrs calibrate` starts a further recording
    (its first sample, the scene's velocities)."""
    model = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, spec["file"]))
    model.opt.integrator = getattr(mujoco.mjtIntegrator, "mjINT_" + args.integrator.upper())
    model.opt.timestep = args.timestep
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    rob = sc["robots"][0]
    ctrl = rob["controller"]
    joints = list(spec["excite"])
    delay, drag = {}, {}
    for _key, value, (what, on) in hidden:
        names = joints if on is None else [on]
        for j in names:
            d = model.joint(j).dofadr[0]
            if what == "damping":
                model.dof_damping[d] += value
            elif what == "frictionloss":
                model.dof_frictionloss[d] += value
            elif what == "armature":
                model.dof_armature[d] += value
            elif what == "delay":
                delay[j] = value
            elif what == "drag":
                drag[j] = value
    if args.solreffriction:
        model.dof_solref[:] = [float(x) for x in args.solreffriction.split(",")]
    data = mujoco.MjData(model)
    init = rob.get("initial", {})
    for j in joints:
        q = init.get(j, {}).get("q", [0.0])[0]
        if initial and j in initial:
            q = initial[j]
        data.qpos[model.joint(j).qposadr[0]] = q
    mujoco.mj_forward(model, data)
    dt_sdrs = spec["dt"]
    gains = ctrl.get("gains", {})
    rng = np.random.default_rng(seed)
    rows, next_sample = [], 0.0
    steps = int(round(args.duration / args.timestep))
    for k in range(steps + 1):
        t = k * args.timestep
        if t >= next_sample - 1e-12:
            rows.append([t] + [data.qpos[model.joint(j).qposadr[0]] + args.noise * rng.standard_normal()
                               for j in joints])
            next_sample += args.period
        if k == steps:
            break
        data.qfrc_applied[:] = 0.0
        for j in joints:
            kp = gains.get(j, {}).get("kp", ctrl.get("kp", 0.0))
            kd = gains.get(j, {}).get("kd", ctrl.get("kd", 0.0))
            # SDRS's delay convention: the channel reads its signal at t − d.
            qs, vs = signal(ctrl["targets"][j], t + args.timestep - delay.get(j, 0.0))
            q = data.qpos[model.joint(j).qposadr[0]]
            v = data.qvel[model.joint(j).dofadr[0]]
            data.qfrc_applied[model.joint(j).dofadr[0]] = (2 * kp * (qs - q) + 2 * kd / dt_sdrs * (vs - v)
                                                           - drag.get(j, 0.0) * v * abs(v))
        mujoco.mj_step(model, data)
    with open(out_csv, "w") as f:
        f.write(",".join(["t"] + joints) + "\n")
        for r in rows:
            f.write(",".join(repr(float(x)) for x in r) + "\n")


def judge_outside(res, hidden, expect):
    """An effect outside the library: `unexplained` (or the library's new
    effect, named alone within 10 %), never a wrong library effect, never
    `none` while the gap stands far above the floor; the residual regression
    names the right joint and term."""
    joint, term = expect
    reg = res.get("residual_regression") or {}
    strongest = reg.get("strongest")
    found = strongest == f"{joint}: {term}"
    fl = res["error_floor"]
    far = fl["gap"] > 2 * fl["floor"]
    why = f"regression: {strongest}"
    if res["verdict"] == "none":
        return not far, f"verdict none with gap {fl['gap'] / fl['floor']:.1f}× the floor; {why}"
    if res["verdict"] == "effect":
        key, value, _ = hidden[0]
        named = sorted(set(k.split(":")[0] for k in res["parameters"]))
        if named != [key]:
            return False, f"wrong library effect {named}; {why}"
        err = abs(res["parameters"][key] / value - 1)
        return err <= 0.10 and found, f"named {key} error {100 * err:.1f} %; {why}"
    return found, f"verdict unexplained; {why}"


def judge(res, hidden, expect=None):
    """(ok, why) against the targets of issue 33."""
    if expect is not None:
        return judge_outside(res, hidden, expect)
    if not hidden:
        return res["verdict"] == "none", f"verdict {res['verdict']}"
    tol = 0.10 if len(hidden) == 1 else 0.15
    if res["verdict"] != "effect":
        return False, f"verdict {res['verdict']}"
    want = sorted(k for k, _, _ in hidden)
    got = sorted(k.split(":")[0] for k in res["parameters"])
    got = sorted(set(got))
    if got != want:
        return False, f"named {got}, want {want}"
    errs = []
    for k, v, _ in hidden:
        fit = res["parameters"][k]
        errs.append(abs(fit / v - 1))
    return max(errs) <= tol, "errors " + ", ".join(f"{100 * e:.1f} %" for e in errs)


def parse_initial(text, robot, spec):
    """`--initial JOINT=VALUE[,JOINT=VALUE…]` → {joint: value}. Each joint
    must be one the robot's excitation drives (the measured coordinates, the
    ones `sdrs calibrate` sets from a further recording's first sample),
    given once, with a finite value inside the MJCF joint's range."""
    model = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, spec["file"]))
    joints = list(spec["excite"])
    out = {}
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        if item.count("=") != 1:
            fail(f"--initial: {item!r} is not JOINT=VALUE (e.g. {joints[0]}=-0.5)")
        j, v = (x.strip() for x in item.split("="))
        if j not in joints:
            fail(f"--initial: {j!r} is not a measured joint of {robot} (its joints: {', '.join(joints)})")
        if j in out:
            fail(f"--initial: joint {j!r} given twice")
        try:
            q = float(v)
        except ValueError:
            fail(f"--initial: {j}={v!r}: the value is not a number (rad or m)")
        if not np.isfinite(q):
            fail(f"--initial: {j}={v}: the value is not finite")
        jid = model.joint(j).id
        if model.jnt_limited[jid]:
            lo, hi = model.jnt_range[jid]
            if not lo < q < hi:
                fail(f"--initial: {j}={q} is outside the joint's range [{lo}, {hi}] in {spec['file']}")
        out[j] = q
    if not out:
        fail("--initial: no JOINT=VALUE given")
    return out


def calibrate(args, scene_path, data, cal, what):
    """`sdrs calibrate` on one or several recordings; its calibration.json."""
    cmd = [args.sdrs, "calibrate", scene_path]
    for d in data:
        cmd += ["--measured", d]
    cmd += ["--out", cal, "-q"]
    if args.effects:
        cmd += ["--effects", args.effects]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"sdrs calibrate ({what}): {r.stderr.strip()}")
    with open(os.path.join(cal, "calibration.json")) as f:
        return json.load(f)


def interval(res, key):
    """(value, low, high) of `key` in a calibration.json, None when not fitted."""
    c = (res.get("confidence") or {}).get(key)
    if c is None:
        return None
    return c["value"], c["low"], c["high"]


def inside(v, iv):
    return iv is not None and iv[1] is not None and iv[1] <= v <= iv[2]


def agreement(ra, rb, rj, hidden):
    """The two-recording rule (issue 33: "fits across two recordings agree
    with the single-recording fits within their intervals"), per hidden
    key: `joint` — the joint fit inside A's and B's 95 % intervals (the
    criterion); `cross` — A's fit inside B's interval and B's inside A's
    (a stricter check, reported beside it). Returns (joint ok, cross ok,
    rows) with rows {key: {a, b, ab: (value, low, high)}}."""
    joint_ok, cross_ok, rows = True, True, {}
    for k, _, _ in hidden:
        a, b, j = interval(ra, k), interval(rb, k), interval(rj, k)
        rows[k] = {"a": a, "b": b, "ab": j}
        if a is None or b is None or j is None:
            joint_ok = cross_ok = False
            continue
        joint_ok &= inside(j[0], a) and inside(j[0], b)
        cross_ok &= inside(a[0], b) and inside(b[0], a)
    return joint_ok, cross_ok, rows


def fmt_iv(iv):
    if iv is None:
        return "not fitted"
    lo = "?" if iv[1] is None else f"{iv[1]:.5g}"
    hi = "?" if iv[2] is None else f"{iv[2]:.5g}"
    return f"{iv[0]:.5g} [{lo}, {hi}]"


def run_two_recordings(args, robot, spec, i, name, hidden, initial, case_dir):
    """Recording A from the model's initial state, B from `initial` (its own
    noise seed); `sdrs calibrate` on A alone, on B alone (the scene started
    at B's state) and on A + B (`--measured A --measured B`, the scene at
    A's state: B is simulated from its first sample, as `sdrs calibrate`
    starts every further recording). Returns the summary entry."""
    scene_a, sc_a = make_scene(args, robot, spec, case_dir)
    scene_b, sc_b = make_scene(args, robot, spec, case_dir, initial, "scene_b.yaml")
    da, db = os.path.join(case_dir, "measured_a.csv"), os.path.join(case_dir, "measured_b.csv")
    simulate_mujoco(args, spec, sc_a, hidden, da, seed=1 + i)
    simulate_mujoco(args, spec, sc_a, hidden, db, seed=101 + i, initial=initial)
    ra = calibrate(args, scene_a, [da], os.path.join(case_dir, "cal_a"), f"{robot} {name} A")
    rb = calibrate(args, scene_b, [db], os.path.join(case_dir, "cal_b"), f"{robot} {name} B")
    rj = calibrate(args, scene_a, [da, db], os.path.join(case_dir, "cal_ab"), f"{robot} {name} A+B")
    judged = {w: judge(r, hidden) for w, r in (("a", ra), ("b", rb), ("ab", rj))}
    joint_ok, cross_ok, rows = agreement(ra, rb, rj, hidden)
    ok = joint_ok and all(j[0] for j in judged.values())
    for w, r in (("A", ra), ("B", rb), ("A+B", rj)):
        fl = r["error_floor"]
        print(f"  {w:<4} verdict {r['verdict']:<11} {r['candidate'] or '-':<40} gap {fl['gap']:.2e} "
              f"floor {fl['floor']:.2e}  {judged[w.lower().replace('+', '')][1]}", flush=True)
    for k, row in rows.items():
        print(f"  {k}: A {fmt_iv(row['a'])}  B {fmt_iv(row['b'])}  A+B {fmt_iv(row['ab'])}", flush=True)
    print(f"{'PASS' if ok else 'MISS'} {robot:<26} {name:<28} two recordings (B from "
          f"{', '.join(f'{j}={q}' for j, q in initial.items())}): joint fit inside both single intervals: "
          f"{'yes' if joint_ok else 'NO'}; each single inside the other's: {'yes' if cross_ok else 'NO'}",
          flush=True)
    return {"robot": robot, "case": name, "mode": "two_recordings", "ok": ok, "initial_b": initial,
            "joint_inside_singles": joint_ok, "singles_inside_each_other": cross_ok,
            "hidden": {k: v for k, v, _ in hidden},
            "fits": {w: {"verdict": r["verdict"], "candidate": r["candidate"], "parameters": r["parameters"],
                         "parameters_at_dt": r.get("parameters_at_dt"), "confidence": r.get("confidence"),
                         "judged": judged[w], "reason": r["reason"], "error_floor": r["error_floor"],
                         "recordings": r.get("recordings")}
                     for w, r in (("a", ra), ("b", rb), ("ab", rj))}}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sdrs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--cases", default="all", choices=["quick", "all"])
    ap.add_argument("--robots", default=",".join(ROBOTS))
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--period", type=float, default=0.01)
    ap.add_argument("--noise", type=float, default=1e-3)
    ap.add_argument("--timestep", type=float, default=1e-4)
    ap.add_argument("--dt", type=float, help="override the SDRS step of every robot (s)")
    ap.add_argument("--only", help="run only the case with this name (e.g. friction_joint0)")
    ap.add_argument("--integrator", default="RK4", choices=["RK4", "implicitfast", "implicit", "Euler"])
    ap.add_argument("--effects", help="candidate effects passed to `sdrs calibrate --effects` (isolating runs)")
    ap.add_argument("--initial", help="JOINT=VALUE[,JOINT=VALUE…]: MuJoCo starts at these joint coordinates (rad or "
                    "m; measured joints of the one robot given by --robots; velocities 0) and so does the case's "
                    "scene; with --two-recordings, the start of recording B only")
    ap.add_argument("--two-recordings", action="store_true",
                    help="per case: recording A from the model's initial state and B from --initial; calibrations "
                    "on A alone, B alone (scene at B's state) and A+B (--measured twice); the joint fit must lie "
                    "inside both single fits' 95 %% intervals (issue 33)")
    ap.add_argument("--solreffriction", help="MuJoCo dof_frictionloss solref 'timeconst,dampratio' "
                    "(default: the model's; a smaller time constant makes the dry friction harder)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    summary, missed = [], 0
    robots = [r for r in args.robots.split(",") if r]
    if args.cases == "quick":
        robots = robots[:1]
    if args.two_recordings and not args.initial:
        fail("--two-recordings needs --initial (recording B's start)")
    if args.initial and len(robots) != 1:
        fail(f"--initial names joints of one robot: give exactly one with --robots (got {', '.join(robots) or 'none'})")
    for robot in robots:
        if robot not in ROBOTS:
            fail(f"unknown robot {robot!r} (robots: {', '.join(ROBOTS)})")
    names = [c[0] for r in robots for c in cases_for(ROBOTS[r])]
    if args.only and args.only not in names:
        fail(f"--only {args.only!r}: no such case (cases: {', '.join(dict.fromkeys(names))})")
    for robot in robots:
        spec = dict(ROBOTS[robot])
        if args.dt:
            spec["dt"] = args.dt
        cases = cases_for(spec)
        if args.cases == "quick":
            cases = cases[:2]
        initial = parse_initial(args.initial, robot, spec) if args.initial else None
        for i, (name, hidden, expect) in enumerate(cases):
            if args.only and name != args.only:
                continue
            case_dir = os.path.join(args.out, f"{robot}_{name}")
            os.makedirs(case_dir, exist_ok=True)
            if args.two_recordings:
                if expect is not None:
                    if args.only:
                        fail(f"--two-recordings: case {name} is outside the library (its rule has no interval to compare)")
                    print(f"skip {robot} {name}: outside the library, no interval to compare", flush=True)
                    continue
                entry = run_two_recordings(args, robot, spec, i, name, hidden, initial, case_dir)
                missed += not entry["ok"]
                summary.append(entry)
                continue
            scene_path, sc = make_scene(args, robot, spec, case_dir, initial)
            data = os.path.join(case_dir, "measured.csv")
            simulate_mujoco(args, spec, sc, hidden, data, seed=1 + i, initial=initial)
            res = calibrate(args, scene_path, [data], os.path.join(case_dir, "cal"), f"{robot} {name}")
            ok, why = judge(res, hidden, expect)
            missed += not ok
            fl = res["error_floor"]
            line = (f"{'PASS' if ok else 'MISS'} {robot:<26} {name:<28} verdict {res['verdict']:<11} "
                    f"{res['candidate'] or '-':<40} gap {fl['gap']:.2e} floor {fl['floor']:.2e} "
                    f"(noise {fl['noise']:.1e}, integrator {fl['integrator_in_gap']:.1e}/{fl['integrator']:.1e}) {why}")
            print(line, flush=True)
            summary.append({"robot": robot, "case": name, "ok": ok, "why": why,
                            "hidden": {k: v for k, v, _ in hidden}, "verdict": res["verdict"],
                            "candidate": res["candidate"], "parameters": res["parameters"],
                            "reason": res["reason"], "error_floor": fl,
                            "strongest": (res.get("residual_regression") or {}).get("strongest")})
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(f"{len(summary) - missed}/{len(summary)} cases meet the targets")
    sys.exit(1 if missed else 0)


if __name__ == "__main__":
    main()
