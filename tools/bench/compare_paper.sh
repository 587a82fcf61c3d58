#!/usr/bin/env bash
# The full paper-suite comparison (robots/compare/paper.yaml): hull sizes
# 8…1024, chains of 2…32 links with both contact models, the co-design
# benchmarks at their full iteration counts. About ten hours on a 2-core
# machine shared with other work (the run of 2026-12-01/02 behind
# docs/results/; nine of them the mesh baseline's rows, measured with IPC's
# projected Newton Hessians, since replaced by the exact ones);
# resumable: run it again with the same output directory after an
# interruption and finished benchmarks (and the finished methods of a
# co-design benchmark) are kept. While it runs, or after it stopped,
# `target/release/sdrs compare --suite paper --out OUT_DIR --report-only`
# writes the report from what has finished.
#
# Usage: tools/bench/compare_paper.sh OUT_DIR
set -euo pipefail
cd "$(dirname "$0")/../.."
out="${1:?usage: tools/bench/compare_paper.sh OUT_DIR}"
cargo build --release -p sdrs-cli
start=$(date +%s)
target/release/sdrs compare --suite paper --out "$out"
echo "paper suite: $(( $(date +%s) - start )) s wall; report in $out/report.html"
