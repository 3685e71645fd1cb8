#!/bin/bash
# Phase 2 of the registered granule screen (docs/results/granule_screen/criterion.md): the
# phase-1 pick (S3: easo, placed nuclei) on five seeds r0-r4, each beside its cohesionless
# twin, and a uniform twin at the pick's mean liquid content (0.012: the mean content of
# S3 r0 at its first production frame, 0.0116, to two significant figures). Phase 1's r0 is
# one of the five (copied in, so it is not run again: the same scene, the same hash).
#   bash scripts/granule_screen_phase2.sh [runs]   # runs/granule_screen/P2 and P2U
set -euo pipefail
out=${1:-runs}/granule_screen
ligwf=${LIGWF:-.venv/bin/ligwf}
easo=(--set scene.liquid.model=easo --set scene.liquid.bridge_volume_fraction=null
      --set scene.liquid.max_liquid_content=null --set scene.liquid.max_separation_ratio=1.3)
five=(--set sweep.replicas=5)
mkdir -p "$out/P2"
[ -d "$out/P2/cg1-none-r0" ] || cp -a "$out/S3/cg1-none-r0" "$out/P2/"
echo "P2 start $(date -u +%FT%TZ)"
$ligwf run workflows/granule_screen.yaml --out "$out/P2" "${easo[@]}" "${five[@]}" \
  --set "sweep.controls=[cohesionless]" > "$out/P2.log" 2>&1 \
  && echo "P2 done $(date -u +%FT%TZ)" || echo "P2 rc=$? $(date -u +%FT%TZ)"
echo "P2U start $(date -u +%FT%TZ)"
$ligwf run workflows/granule_screen.yaml --out "$out/P2U" "${easo[@]}" "${five[@]}" \
  --set scene.liquid.placement=uniform --set scene.liquid.wet_granules=null \
  --set scene.liquid.liquid_content=0.012 > "$out/P2U.log" 2>&1 \
  && echo "P2U done $(date -u +%FT%TZ)" || echo "P2U rc=$? $(date -u +%FT%TZ)"
