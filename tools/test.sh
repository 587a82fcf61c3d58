#!/usr/bin/env bash
# The whole test suite, on a fresh clone: installs what the tests need
# (Debian packages such as chromium, then the Python helpers' packages into
# .venv/, and the `sdrs` Python package built from python/), then runs
# every Rust test, then the Python package's pytest suite (python/tests/;
# torch and ray are required there: a missing one fails, never skips).
# `.ci/run` calls exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each phase prints the time at which it ended (where CI's 30 minutes go:
# notes/ci-time.md).
start=$SECONDS
phase() { echo "test.sh: $1 done at $((SECONDS - start)) s"; }
bash tools/setup/setup_system.sh
bash tools/setup/setup_python.sh
phase "setup (Python packages, the sdrs Python package)"
# The release profile: the same build as the README's main command
# (`cargo run --release`), so a fresh clone compiles the project once.
# The workspace includes the Python package's crate (python/): give cargo
# the environment maturin gave it in setup_python.sh, so the PyO3 crates
# built there are reused instead of rebuilt (pyo3 rebuilds when these change).
export PYO3_PYTHON="$PWD/.venv/bin/python" PYTHON_SYS_EXECUTABLE="$PWD/.venv/bin/python"
export PYO3_BUILD_EXTENSION_MODULE=1
PYO3_ENVIRONMENT_SIGNATURE="$("$PYO3_PYTHON" -c 'import platform, sys; v = sys.version_info; print(f"{sys.implementation.name}-{v[0]}.{v[1]}-{platform.architecture()[0]}")')"
export PYO3_ENVIRONMENT_SIGNATURE
# Every tier: a test that needs .venv or Chromium fails instead of skipping
# (tests/common/mod.rs, `skip_without_venv`).
export SDRS_TEST_ALL_TIERS=1
# cargo-nextest (on every machine of this kind) runs the tests of all the
# targets as one pool, each test in its own process, so the long single-test
# targets overlap with the rest: 825 s of tests against cargo test's ~1036 s
# on 2 cores (2026-11-30, notes/ci-time.md). Plain cargo test where it is
# missing.
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --release --workspace --all-targets
else
  cargo test --release --workspace --all-targets
fi
phase "Rust build and tests"
# The Python package (PyO3): simulate vs the CLI, gradients, the torch
# operator (gradcheck), errors, Ray sweeps on a local 2-CPU cluster.
# The Rust tests above built the CLI the Python tests compare against.
SDRS_CLI="$PWD/${CARGO_TARGET_DIR:-target}/release/sdrs" \
  .venv/bin/python -m pytest python/tests -q -p no:cacheprovider
phase "pytest"
