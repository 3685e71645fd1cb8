#!/usr/bin/env bash
# Runs the three studies behind docs/results/gsd_cg/ (issue "Granules that exist", item 4),
# one after another on the planner's default path (ligwf study: run, analyse, report):
#   OUT/main : workflows/gsd_cg.yaml (2 CG1 replicas + their cohesionless twins, 4 We-CG2,
#              4 Bo-CG2, 36 mm slice)
#   OUT/L2   : We-CG2 in a 2x longer slice (72 mm), 2 replicas
#   OUT/L4   : We-CG2 in a 4x longer slice (144 mm), 2 replicas
# Then: .venv/bin/python scripts/gsd_cg_claim.py OUT --out docs/results/gsd_cg
# About 25 min wall on 2 idle cores (ligwf check's estimate).
set -euo pipefail
out=${1:-runs/gsd_cg}
LIGWF=${LIGWF:-.venv/bin/ligwf}
mkdir -p "$out"
"$LIGWF" study workflows/gsd_cg.yaml --out "$out/main" >"$out/main.log" 2>&1
for k in 2 4; do
  length=$(python3 -c "print(0.036 * $k)")
  "$LIGWF" study workflows/gsd_cg.yaml --out "$out/L$k" \
    --set "scene.drum.length=$length" --set "sweep.cg_levels=[2]" --set "sweep.rules=[weber]" \
    --set "sweep.replicas=2" --set "sweep.controls=[]" >"$out/L$k.log" 2>&1
done
