#!/usr/bin/env bash
# The results page docs/results/ (report.md, report.html, tables/, plots/),
# rendered from docs/results/results.json by `sdrs compare --render`; never
# edit those files by hand (cli/tests/compare.rs checks report.md).
# After a new paper-suite run (tools/bench/compare_paper.sh OUT):
#   cp OUT/results.json docs/results/ && cp OUT/plots/shapes_*.svg docs/results/plots/
#   bash tools/gen/render_results.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release -p sdrs-cli
target/release/sdrs compare --render docs/results/results.json --out docs/results
