#!/usr/bin/env bash
# Long fuzzing run of the scene, URDF and mesh readers (tests/fuzz_inputs.rs):
# CASES mutated inputs per reader (default 200000, about 30 minutes on two
# cores). CI runs the same test with 150 cases per reader.
set -euo pipefail
cd "$(dirname "$0")/.."
cases="${1:-200000}"
start=$(date +%s)
SDRS_FUZZ_CASES="$cases" cargo test --release --test fuzz_inputs -- --nocapture
echo "fuzz: $cases cases per reader (3 readers) in $(( $(date +%s) - start )) s, no panic, no hang"
