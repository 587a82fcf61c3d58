"""Shared start of the Pinocchio cross-checks (check_fk_pinocchio.py,
check_mass_matrix_pinocchio.py): the command line `ROBOT.urdf SAMPLES.json
[--tol T]`, Pinocchio's model of the URDF and the sampled configurations.
Exits 3 when a package is missing and 2 when the samples file is empty, as
the checks document."""
import argparse
import json
import sys

try:
    import numpy  # noqa: F401  (the checks use it; fail here with the same message)
    import pinocchio as pin
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e.name} (needed by {sys.argv[0]})", file=sys.stderr)
    sys.exit(3)


def load(description):
    """Returns (args, model, data, samples); exits 2 when there are no samples."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("urdf")
    ap.add_argument("samples")
    ap.add_argument("--tol", type=float, default=1e-9)
    a = ap.parse_args()
    model = pin.buildModelFromUrdf(a.urdf)
    data = model.createData()
    with open(a.samples) as f:
        samples = json.load(f)["configurations"]
    if not samples:
        print("no configurations in the samples file", file=sys.stderr)
        sys.exit(2)
    return a, model, data, samples
