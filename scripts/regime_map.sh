#!/usr/bin/env bash
# Runs the CG1 regime map of docs/results/granule_definitions.md: workflows/regime.yaml once
# per regime point (wet, and its cohesionless twin where listed), two queues side by side
# (one core each; --bind-to none so the two mpirun -np 1 do not share core 0).
# Usage: scripts/regime_map.sh OUT_DIR   (then: python scripts/regime_map.py OUT_DIR)
set -euo pipefail
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
queue_a() {
  one wet_mu0.3 scene.liquid.viscosity=0.3
  one twin_mu0.3 scene.liquid.viscosity=3.0e-4 scene.liquid.surface_tension=2.4e-5
  one wet_mu0.01 scene.liquid.viscosity=0.01
  one wet_mu0.3_lc0.05 scene.liquid.viscosity=0.3 scene.liquid.liquid_content=0.05
}
queue_b() {
  one wet_mu0.001 scene.liquid.viscosity=0.001
  one twin_mu0.001 scene.liquid.viscosity=1.0e-6 scene.liquid.surface_tension=2.4e-5
  one wet_mu0.1 scene.liquid.viscosity=0.1
  one wet_mu0.3_gamma0.072 scene.liquid.viscosity=0.3 scene.liquid.surface_tension=0.072
}
queue_a & queue_b & wait
# liquid placed as pre-formed wet granules in a dry bed (3 spheres of 3.5 mm, content 0.05:
# ~8 % of the bed), binder-like and water-like, with the twin of the binder-like one
placed="scene.liquid.placement=granules"
wg="scene.liquid.wet_granules={count: 3, radius: 0.0035, liquid_content: 0.05}"
if [ "${PLACED:-1}" = 1 ]; then
  ( one placed_mu0.3 "$placed" "$wg" scene.liquid.viscosity=0.3
    one placed_twin_mu0.3 "$placed" "$wg" scene.liquid.viscosity=3.0e-4 scene.liquid.surface_tension=2.4e-5
    one placed_mu0.001 "$placed" "$wg" scene.liquid.viscosity=0.001 ) &
  wait
fi
