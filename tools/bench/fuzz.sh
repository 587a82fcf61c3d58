#!/usr/bin/env bash
# Long fuzzing run of the scene, URDF and mesh readers (tests/fuzz_inputs.rs).
#
#   bash tools/bench/fuzz.sh [CASES] [SECONDS]
#
# Each reader runs rounds of CASES freshly seeded mutated inputs (default
# 5000) until SECONDS have passed (default 1800: the three readers run side by
# side, each for at least 30 minutes), and prints how many cases it ran.
# With SECONDS = 0 each reader runs one round. CI runs one round of 150.
set -euo pipefail
cd "$(dirname "$0")/../.."
cases="${1:-5000}"
seconds="${2:-1800}"
start=$(date +%s)
env_seconds=()
if [ "$seconds" != 0 ]; then env_seconds=(SDRS_FUZZ_SECONDS="$seconds"); fi
env SDRS_FUZZ_CASES="$cases" "${env_seconds[@]}" \
  cargo test --release --test integration -- --nocapture --test-threads 3 fuzz_inputs:: 2>&1 | tee target/fuzz.log
echo "fuzz: 3 readers in $(( $(date +%s) - start )) s; cases per reader above ('fuzz <reader>: N cases'), no panic, no hang"
