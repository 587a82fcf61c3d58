"""The table of `tools/bench/multistart.sh`: one row per run, and the pick.

    python tools/bench/multistart_table.py OUT MODE [MODE ...] -- SEED [SEED ...] [--exclude grasp|upright]

Reads OUT/start_S/summary.json (the perturbed start, `--iters 0`) and
OUT/<mode>_S/summary.json + history.csv. The pick per mode is the seed with
the lowest best loss (the loss chooses; a task metric never does). Grasping
tasks get their grasp count and the designed links' topology, locomotion
tasks their distance and whether the robot is upright at the horizon.
`--exclude` drops from the pick every seed whose start already meets the
task's goal, the paper's premise for that task (registered per task in
notes/multistart-design-noise.md): `grasp`, a start that grasps any object;
`upright`, a start upright at the horizon. Excluded seeds are still run and
listed. Writes OUT/pick.json; prints a markdown table.
"""
import json
import sys
from pathlib import Path


def best_loss(d):
    s = json.loads((d / "summary.json").read_text())
    best, it = s["initial_loss"], 0
    hist = d / "history.csv"
    if hist.exists():
        for row in hist.read_text().splitlines()[1:]:
            cols = row.split(",")  # iteration, loss, best_loss, ...
            if float(cols[1]) < best:
                best, it = float(cols[1]), int(cols[0])
    return s, best, it


def outcome(s, key):
    """The task metric of the returned iterate (`after`) or the start (`before`)."""
    m = s.get("extra", {}).get("metrics", {})
    parts = []
    if m.get("grasp", {}).get("trajectories"):
        g = m["grasp"]
        n = g["grasped_before"] if key == "before" else g["grasped_after"]
        parts.append(f"{n}/{g['trajectories']} grasped")
    if "topology" in m:
        betti = lambda x: f"({x['components']},{x['holes']},{x['cavities']})"
        parts.append(" ".join(f"{k.split('/')[-1]} {betti(v)}" for k, v in m["topology"][key].items()))
    loco = m.get("initial" if key == "before" else "final")
    if isinstance(loco, dict) and "distance" in loco:
        up = "upright" if loco["upright_at_horizon"] else f"falls at {loco['first_fall_time']:.2f} s"
        parts.append(f"{loco['distance']:.3f} m, {up}")
    return "; ".join(parts) or "—"


def premise_fails(start, rule):
    """Whether a start already meets the goal that `rule` names."""
    m = start.get("extra", {}).get("metrics", {})
    if rule == "grasp":
        return m.get("grasp", {}).get("grasped_before", 0) > 0
    if rule == "upright":
        return bool(m["initial"]["upright_at_horizon"])
    return False


def main():
    args = sys.argv[1:]
    rule = None
    if "--exclude" in args:
        k = args.index("--exclude")
        rule = args[k + 1]
        if rule not in ("grasp", "upright"):
            sys.exit(f"--exclude: grasp or upright, got {rule!r}")
        del args[k : k + 2]
    out, rest = Path(args[0]), args[1:]
    cut = rest.index("--")
    modes, seeds = rest[:cut], rest[cut + 1 :]
    print("| seed | start (`--iters 0`) | mode | loss initial → best (iteration) | outcome of the returned iterate | wall (s) |")
    print("|---|---|---|---|---|---|")
    picks = {}
    for m in modes:
        for sd in seeds:
            st = out / f"start_{sd}" / "summary.json"
            excluded = False
            if st.exists():
                sj = json.loads(st.read_text())
                start = outcome(sj, "before")
                excluded = rule is not None and premise_fails(sj, rule)
                if excluded:
                    start += " (**excluded**: the start meets the goal)"
            else:
                start = "missing"
            d = out / f"{m}_{sd}"
            if not (d / "summary.json").exists():
                print(f"| {sd} | {start} | {m} | failed: see {d}.log | | |")
                continue
            s, best, it = best_loss(d)
            wall = (out / f"{m}_{sd}.wall").read_text().strip()
            print(f"| {sd} | {start} | {m} | {s['initial_loss']:.4e} → {best:.4e} ({it}) | {outcome(s, 'after')} | {wall} |")
            if not excluded and (m not in picks or best < picks[m]["best_loss"]):
                picks[m] = {"seed": int(sd), "best_loss": best, "iteration": it, "outcome": outcome(s, "after")}
    print()
    for m, p in picks.items():
        print(f"pick ({m}): seed {p['seed']}, best loss {p['best_loss']:.4e} at iteration {p['iteration']}: {p['outcome']}")
    (out / "pick.json").write_text(json.dumps(picks, indent=1) + "\n")


if __name__ == "__main__":
    main()
