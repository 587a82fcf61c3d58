#!/usr/bin/env bash
# The whole test suite, on a fresh clone: installs what the tests need
# (the Python helpers' packages into .venv/, when tools/ has them), then runs
# every Rust test. `.ci/run` calls exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -f tools/setup_python.sh ]; then
  bash tools/setup_python.sh
fi
# The release profile: the same build as the README's main command
# (`cargo run --release`), so a fresh clone compiles the project once.
cargo test --release --workspace --all-targets
