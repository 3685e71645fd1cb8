#!/bin/bash
# Phase 1 of the registered granule screen (docs/results/granule_screen/criterion.md):
# one seed of each of the four conditions, two at a time (each a 1-rank run).
#   bash scripts/granule_screen.sh [runs]      # runs/granule_screen/S1..S4
set -euo pipefail
out=${1:-runs}/granule_screen
ligwf=${LIGWF:-.venv/bin/ligwf}
easo=(--set scene.liquid.model=easo --set scene.liquid.bridge_volume_fraction=null
      --set scene.liquid.max_liquid_content=null --set scene.liquid.max_separation_ratio=1.3)
uniform=(--set scene.liquid.placement=uniform --set scene.liquid.wet_granules=null)
run() { local name=$1; shift; echo "$name start $(date -u +%FT%TZ)";
        $ligwf run workflows/granule_screen.yaml --out "$out/$name" "$@" > "$out/$name.log" 2>&1 \
          && echo "$name done $(date -u +%FT%TZ)" || echo "$name rc=$? $(date -u +%FT%TZ)"; }
mkdir -p "$out"
# the placed-nuclei conditions first (the pilot bound a uniformly wet bed into one mass)
run S1 &
run S3 "${easo[@]}" &
wait
run S2 "${uniform[@]}" &
run S4 "${easo[@]}" "${uniform[@]}" &
wait
