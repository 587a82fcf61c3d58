#!/usr/bin/env bash
# Newton iterations per step on every bundled scene (robots/**/*.yaml with
# robots or objects), before and after issue 18's solver changes: each scene
# is simulated with the paper's Newton (`solver: {predictor: previous,
# indefinite: clamp}`: start at θ^t, clamp eigenvalues) and with the
# defaults (`extrapolate`: start at 2θ^t − θ^{t−1}; `shift`: Cholesky of
# H + τI on indefinite blocks), the scene's other settings unchanged, for
# min(scene steps, --steps) steps. Prints mean / max
# iterations per step, ms/step and the largest final-state difference
# between the two runs (the solution is the same to within the Newton
# tolerance per step; over many steps of a chaotic scene the difference
# grows like any round-off).
#
# `--before` / `--after PREDICTOR/INDEFINITE` compare two other solver settings
# (e.g. `--before quadratic/shift --after cubic/shift`); the defaults are the
# comparison above.
#
#   tools/bench/newton_iters.sh [--steps 300] [--sdrs target/release/sdrs] [--json out.json]
#                               [--before previous/clamp] [--after extrapolate/shift]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$(dirname "$here")")"
steps=300
sdrs="$root/target/release/sdrs"
json=""
before="previous/clamp"
after="extrapolate/shift"
while [ $# -gt 0 ]; do
  case "$1" in
    --steps) steps="$2"; shift 2 ;;
    --sdrs) sdrs="$2"; shift 2 ;;
    --json) json="$2"; shift 2 ;;
    --before) before="$2"; shift 2 ;;
    --after) after="$2"; shift 2 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
py="${PYTHON:-$root/.venv/bin/python}"
[ -x "$py" ] || py=python3
[ -x "$sdrs" ] || { echo "no sdrs binary at $sdrs (cargo build --release)" >&2; exit 2; }
echo "load: $(uptime)"
echo "before: $before, after: $after"
"$py" - "$root" "$sdrs" "$steps" "$json" "$before" "$after" <<'EOF'
import glob, json, os, subprocess, sys, tempfile
import yaml

root, sdrs, cap, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
settings = {"before": tuple(sys.argv[5].split("/")), "after": tuple(sys.argv[6].split("/"))}
scenes = []
for p in sorted(glob.glob(os.path.join(root, "robots", "**", "*.yaml"), recursive=True)):
    with open(p) as f:
        try:
            spec = yaml.safe_load(f)
        except yaml.YAMLError:
            continue
    if isinstance(spec, dict) and ("robots" in spec or "objects" in spec) and "version" in spec:
        scenes.append((p, spec))
rows = []
print("| scene | steps | it/step before | it/step after | max before | max after | ms/step before | ms/step after | max final Δθ |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for path, spec in scenes:
    rel = os.path.relpath(path, root)
    steps = min(int(spec.get("steps", cap)), cap)
    res = {}
    for label in ("before", "after"):
        pred, ind = settings[label]
        s = dict(spec)
        s["solver"] = dict(s.get("solver") or {}, predictor=pred, indefinite=ind)
        # Next to the original, so relative mesh paths resolve.
        fd, tmp = tempfile.mkstemp(suffix=".yaml", prefix=".newton_iters_", dir=os.path.dirname(path))
        with os.fdopen(fd, "w") as f:
            yaml.safe_dump(s, f, sort_keys=False)
        try:
            with tempfile.TemporaryDirectory() as d:
                sj = os.path.join(d, "summary.json")
                r = subprocess.run([sdrs, "simulate", tmp, "--steps", str(steps), "--json", sj, "-q"],
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    res[label] = {"error": (r.stderr.strip().splitlines() or ["?"])[-1]}
                    continue
                with open(sj) as f:
                    res[label] = json.load(f)
        finally:
            os.unlink(tmp)
    b, a = res["before"], res["after"]
    if "error" in b or "error" in a:
        print(f"| {rel} | {steps} | {b.get('error', '')} | {a.get('error', '')} | | | | | |")
        rows.append({"scene": rel, "steps": steps, "before": b.get("error"), "after": a.get("error")})
        continue
    fb, fa = b["final_state"], a["final_state"]
    diff = max((abs(fb[k] - fa[k]) for k in fb if k in fa and k != "t"), default=0.0)
    nb, na = b["newton"], a["newton"]
    print(f"| {rel} | {steps} | {nb['mean_iterations']:.2f} | {na['mean_iterations']:.2f} | "
          f"{nb['max_iterations']} | {na['max_iterations']} | {1e3 * b['seconds_per_step']:.3f} | "
          f"{1e3 * a['seconds_per_step']:.3f} | {diff:.1e} |")
    rows.append({"scene": rel, "steps": steps,
                 "before": {"mean_iterations": nb["mean_iterations"], "max_iterations": nb["max_iterations"],
                            "ms_per_step": 1e3 * b["seconds_per_step"]},
                 "after": {"mean_iterations": na["mean_iterations"], "max_iterations": na["max_iterations"],
                           "ms_per_step": 1e3 * a["seconds_per_step"]},
                 "max_final_state_difference": diff})
if out:
    with open(out, "w") as f:
        json.dump(rows, f, indent=1)
EOF
