#!/usr/bin/env bash
# Runs the CG1 regime map of docs/results/granule_definitions.md: workflows/regime.yaml once
# per regime point (wet beds, their cohesionless twins with surface tension and viscosity
# / 1000, and a dry bed with pre-formed wet granules), two at a time (one core each;
# --bind-to none so two mpirun -np 1 do not share core 0). About 10 core-min a point.
# Usage: scripts/regime_map.sh OUT_DIR   (then: .venv/bin/python scripts/regime_map.py OUT_DIR DOC_DIR)
set -uo pipefail
out=${1:-runs/regime}
mkdir -p "$out"
LIGWF=${LIGWF:-.venv/bin/ligwf}
export LIGWF_MPIRUN_ARGS="--bind-to none"
one() {  # name, then --set values
  local name=$1; shift
  local sets=()
  for kv in "$@"; do sets+=(--set "$kv"); done
  if [ -f "$out/$name/.done" ]; then return; fi
  "$LIGWF" run workflows/regime.yaml --out "$out/$name" --np 1 "${sets[@]}" >"$out/$name.log" 2>&1 \
    && touch "$out/$name/.done" || echo "$name failed" >>"$out/failed.txt"
}
placed="scene.liquid.placement=granules"
wg="scene.liquid.wet_granules={count: 3, radius: 0.0035, liquid_content: 0.05}"
queue_a() {
  one wet_mu0.3 scene.liquid.viscosity=0.3
  one twin_mu0.3 scene.liquid.viscosity=3.0e-4 scene.liquid.surface_tension=2.4e-5
  one wet_mu0.01 scene.liquid.viscosity=0.01
  one wet_mu0.3_lc0.05 scene.liquid.viscosity=0.3 scene.liquid.liquid_content=0.05
  one placed_mu0.3 "$placed" "$wg" scene.liquid.viscosity=0.3
  one placed_mu0.001 "$placed" "$wg" scene.liquid.viscosity=0.001
}
queue_b() {
  one wet_mu0.001 scene.liquid.viscosity=0.001
  one twin_mu0.001 scene.liquid.viscosity=1.0e-6 scene.liquid.surface_tension=2.4e-5
  one wet_mu0.1 scene.liquid.viscosity=0.1
  one wet_mu0.3_gamma0.072 scene.liquid.viscosity=0.3 scene.liquid.surface_tension=0.072
  one placed_twin_mu0.3 "$placed" "$wg" scene.liquid.viscosity=3.0e-4 scene.liquid.surface_tension=2.4e-5
  # the strongest bed in a slice twice as long (24 diameters): do its granules still wrap?
  one wet_mu0.3_gamma0.072_L2 scene.liquid.viscosity=0.3 scene.liquid.surface_tension=0.072 \
    scene.drum.length=0.036
}
queue_a & queue_b & wait
