#!/usr/bin/env bash
# The whole test suite, on a fresh clone: installs what the tests need
# (Debian packages such as chromium, then the Python helpers' packages into
# .venv/), then runs
# every Rust test. `.ci/run` calls exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup_system.sh
bash tools/setup_python.sh
# The release profile: the same build as the README's main command
# (`cargo run --release`), so a fresh clone compiles the project once.
cargo test --release --workspace --all-targets
