#!/usr/bin/env bash
# Lift capacity of a parallel-jaw design (issue 30): each object's mass set to
# 2, 5, 10, 20, 30 and 50 g in its scene, 180 steps simulated, and the rise of
# the object's COM after the lift's start (step 60) printed (≥ 0.05 m: lifted).
#
#   bash tools/bench/grasp_capacity.sh SCENE_DIR TAG
#
# SCENE_DIR holds scene_{cube,cylinder,ball,plus}.yaml: the committed
# robots/parallel_jaw_gripper (the initial design) or an optimize run's
# scenes/ (the optimized one). Uses target/release/sdrs; writes only temporary
# files next to the scenes (removed) and /tmp/grasp_capacity.csv.
set -euo pipefail
B=${SDRS:-$(cd "$(dirname "$0")/../.." && pwd)/target/release/sdrs}
dir=$1; tag=${2:-design}
for o in cube cylinder ball plus; do
  src=$dir/scene_$o.yaml
  line=$(grep -n "^- name: $o" "$src" | cut -d: -f1); ml=$((line + 1))
  out=""
  for m in 0.002 0.005 0.01 0.02 0.03 0.05; do
    tmp=$(dirname "$src")/_capacity_$o.yaml
    sed "${ml}s/mass: .*/mass: $m/" "$src" > "$tmp"
    if "$B" simulate "$tmp" --steps 180 --out /tmp/grasp_capacity.csv -q >/dev/null 2>&1; then
      col=$(head -1 /tmp/grasp_capacity.csv | tr ',' '\n' | grep -n "^$o/$o:z$" | cut -d: -f1)
      out="$out $m:$(awk -F, -v c="$col" 'NR==62{z=$c} END{printf "%.3f", $c-z}' /tmp/grasp_capacity.csv)"
    else
      out="$out $m:fail"
    fi
    rm -f "$tmp"
  done
  echo "$tag $o: rise after step 60 (m) by mass (kg):$out"
done
