"""Dimensionless numbers of a wet drum, and whether the regime map expects granules there.

For equal spheres of radius R and density rho, at the drum's wall speed v = omega D / 2
(the scale of the collision speeds in the flowing layer), R* = R / 2:

* viscous Stokes number, as the ENGINE's viscous force makes it (``stokes_viscous``, the
  number ``ligwf check`` prints and grades): St_v = St_v,Ennis / J. Ennis, Tardos and
  Pfeffer's (1991) St_v,Ennis = 8 rho R v / (9 mu) (``stokes_viscous_ennis``) is the
  collision momentum over the impulse scale 6 pi mu R*^2 of pure lubrication, whose
  critical value carries ln(h_0 / h_a) (bridge length over asperity height). The engine
  applies 6 pi mu R* v_n / max(s_min, h / R*) (s_min = ``liquid.min_separation_ratio``),
  so one traverse of a bridge of length x_0 R* removes 6 pi mu R*^2 v J with
  J = 1 + ln(x_0 / s_min) if s_min < x_0 (lubrication), x_0 / s_min otherwise (Stokes drag,
  lubrication off: ligwf's default 1.01) -- :func:`ligwf.liquids.capillary.viscous_path_integral`.
  x_0 (``bridge_gap_ratio``) is where the engine's bridge ends: the law's rupture gap or the
  cut at ``max_separation_ratio``, whichever is shorter. So St_v < 1 means the engine's
  viscous force alone stops a collision at relative speed 2v inside one bridge; Ennis's
  sticking criterion St_v,Ennis < (1 + 1/e) ln(h_0 / h_a) reads St_v < 1 + 1/e for washino,
  whose bridge forms on approach, and St_v < 1/e for easo, whose bridge forms only at
  contact (no viscous force on approach; docs/guide/scaling.md);
* granular Bond number Bo_g = F_cap / (m g) = 3 gamma cos(theta) / (4 R^2 rho g), with the
  touching capillary force 2 pi R* gamma cos(theta): cohesion against weight;
* capillary number Ca = mu v / gamma: viscous against capillary forces in a bridge;
* Froude number Fr = omega^2 (D / 2) / g (the flow regime of the drum).

Under Weber scaling (gamma, mu x n) St_v and Ca are CG-invariant and Bo_g falls as 1/n;
under Bond scaling (gamma, mu x n^2) Bo_g is invariant and St_v falls as 1/n (J depends
on gap ratios only, unchanged by CG). The numbers of the ORIGINAL (CG1) particles decide
whether the bed granulates; ``ligwf check`` prints both.

:data:`GRANULATING_ST_V` and :data:`GRANULATING_BOND` bound the region of the regime map
(docs/results/granule_definitions.md, "Regime map") that came CLOSEST to granulation:
binder-like viscosity AND strong cohesion (St_v,Ennis 0.35, Bo_g 3.4 on the demo drum; the
engine's St_v 0.88 there: s_min 1.01, x_0 0.4, J 0.396), where the granules of ``held``
over 1 s beat the cohesionless twin in share, co-movement and reproducibility, but did not
survive a quarter revolution once the slice was long enough (24 diameters) for them not to
wrap the periodic axis. Nowhere on the map (St_v,Ennis 0.35-105, Bo_g 1.1-3.4, liquid 2-5 %,
uniform or placed liquid, all with lubrication off) did any definition pass every
pre-registered criterion, so every granule analysis is warned. docs/results quotes the
map's points in St_v,Ennis (its regeneration script reads ``stokes_viscous_ennis``).
"""

from __future__ import annotations

import math

from ligwf.liquids.capillary import viscous_path_integral

GRAVITY = 9.81

#: the closest region to granulation on the regime map: the engine's St_v <= this (the
#: map's St_v,Ennis 0.5 with lubrication off, x_0 0.4: 0.5 / 0.396) ...
GRANULATING_ST_V = 1.25
#: ... and Bo_g >= this (CG1 numbers; docs/results/granule_definitions.md)
GRANULATING_BOND = 3.0
#: the map's runs had min_separation_ratio 1.01 (lubrication off)
MAP_MIN_SEPARATION_RATIO = 1.01

#: what the registered granule screen found with lubrication on (docs/results/granule_screen;
#: tests/scene/test_regime.py reads these against its committed tables): phase 2's five
#: seeds of the pick (easo, placed nuclei) -- mean survival and co-movement ratio, the wet
#: beds' held share and their uniform twins' -- and the beads wet at the start and the end
SCREEN_SURVIVAL, SCREEN_COMOVEMENT = 0.30, 0.59
SCREEN_SHARE, SCREEN_UNIFORM_SHARE = 0.32, 0.40
SCREEN_WET_START, SCREEN_WET_END = 0.06, 1.0
SCREEN_FINDING = (
    "with lubrication on, the registered granule screen (docs/results/granule_screen: CG1, "
    "2 mm beads, liquid content 0.2, 0.1 Pa s, s_min 0.02, 30 revolutions) found no growth: "
    "uniformly wet beds (washino, easo) bound into one mass spanning the slice; placed wet "
    f"nuclei (easo, 5 seeds) spread their liquid from {SCREEN_WET_START:.0%} to "
    f"{SCREEN_WET_END:.0%} of the beads, their held granules (share {SCREEN_SHARE:.2f}) "
    f"neither survived (mean survival {SCREEN_SURVIVAL:.2f} < 0.5) nor moved together "
    f"(co-movement {SCREEN_COMOVEMENT:.2f} > 0.5), and the same liquid spread uniformly held "
    f"more ({SCREEN_UNIFORM_SHARE:.2f}); washino with placed nuclei went unstable")


def bridge_gap_ratio(s, radius: float) -> float:
    """x_0: where the engine's bridge between two particles of ``radius`` (m) at the case's
    liquid content ends, as a gap over R* = radius / 2: the law's rupture gap or the cut at
    ``max_separation_ratio`` x (r_i + r_j), whichever comes first."""
    liq = s.liquid_values
    theta = math.radians(liq.contact_angle_deg)
    volume = s.liquid.bridge_volume(radius, radius, liq.liquid_content, liq.liquid_content)
    rupture = float(s.liquid.rupture_distance(volume, theta))
    cut = s.liquid.engine_cutoff_gaps(radius, liq.max_separation_ratio)[0]
    return min(rupture, cut) / (0.5 * radius)


def regime_numbers(s) -> dict[str, float]:
    """St_v (the engine's), St_v,Ennis, Bo_g, Ca and Fr of a
    :class:`~ligwf.scene.scaled.ScaledScene` (its own, scaled particles), for the
    number-mean radius; with the bridge length x_0 and the viscous path integral J that
    turn St_v,Ennis into the engine's St_v (module docstring)."""
    p, liq = s.particles, s.liquid_values
    radius = 0.5 * sum(d * f for d, f in zip(p.diameters, p.number_fractions))
    v = float(s.drum.omega) * 0.5 * float(s.drum.diameter)
    wet = liq.model != "none" and liq.surface_tension > 0
    theta = math.radians(liq.contact_angle_deg)
    mu, gamma = float(liq.viscosity), float(liq.surface_tension)
    ennis = 8.0 * p.density * radius * v / (9.0 * mu) if wet and mu > 0 else math.inf
    x_0 = bridge_gap_ratio(s, radius) if wet else 0.0
    path = viscous_path_integral(x_0, liq.min_separation_ratio) if wet else 0.0
    stokes = ennis / path if wet and mu > 0 else math.inf
    bond = 3.0 * gamma * math.cos(theta) / (4.0 * radius ** 2 * p.density * GRAVITY) if wet else 0.0
    capillary = mu * v / gamma if wet else 0.0
    return {"stokes_viscous": stokes, "stokes_viscous_ennis": ennis,
            "bridge_gap_ratio": x_0, "viscous_path_integral": path,
            "min_separation_ratio": float(liq.min_separation_ratio),
            "bond_granular": bond, "capillary": capillary, "froude": float(s.drum.froude),
            "liquid_content": float(liq.liquid_content) if wet else 0.0}


def granulation_warning(numbers: dict[str, float]) -> str:
    """What the regime map says about granules at these CG1 numbers (always a warning: no
    mapped regime passed every control criterion)."""
    st, bo = numbers["stokes_viscous"], numbers["bond_granular"]
    if bo <= 0:
        return "the bed is dry: there are no liquid bridges, hence no granules to analyse"
    s_min = numbers.get("min_separation_ratio", MAP_MIN_SEPARATION_RATIO)
    unmapped = "" if s_min >= 1.0 else (
        f" (min_separation_ratio = {s_min:g} switches the engine's lubrication on; the map "
        f"was measured with it off, {MAP_MIN_SEPARATION_RATIO:g}: its verdict there is an "
        f"extrapolation; {SCREEN_FINDING})")
    if st <= GRANULATING_ST_V and bo >= GRANULATING_BOND:
        return (f"St_v = {st:.3g}, Bo_g = {bo:.3g} is the regime map's closest point to "
                "granulation (docs/results/granule_definitions.md): granules held for 1 s beat "
                "a cohesionless twin in share and co-movement there but did not survive a "
                "quarter revolution; check yours with sweep.controls: [cohesionless]"
                + unmapped)
    return (f"St_v = {st:.3g}, Bo_g = {bo:.3g}: no granule definition beat a cohesionless "
            "control in this regime (docs/results/granule_definitions.md: binder-like "
            f"viscosity, the engine's St_v <= {GRANULATING_ST_V:g}, with strong cohesion "
            f"Bo_g >= {GRANULATING_BOND:g} came closest); a granule analysis here measures "
            "the definition, not granulation" + unmapped)


def original_numbers(case) -> dict[str, float]:
    """:func:`regime_numbers` of a workflow case's ORIGINAL (CG1) particles."""
    from dataclasses import replace

    from ligwf.scene.scaling import Rule

    return regime_numbers(replace(case, cg=1.0, rule=Rule.NONE).scaled())


def regime_warnings(rendered) -> list[str]:
    """One warning per distinct CG1 regime of the cases that ask for granule analysis
    (contact dumps on; control twins left out: they are meant to have no granules)."""
    out: list[str] = []
    for rc in rendered:
        if not rc.scaled.contact_dumps or any(k == "control" for k, _ in rc.case.varied):
            continue
        msg = granulation_warning(original_numbers(rc.case))
        if all(not w.endswith(msg) for w in out):
            out.append(f"{rc.case.case_id}: granule analysis asked for, but {msg}")
    return out


def definition_warning(settings, rendered) -> list[str]:
    """A warning when granules are analysed with a definition that never beat the
    cohesionless control on the regime map (every one but ``held``)."""
    if getattr(settings, "granules", "held") == "held":
        return []
    if not any(rc.scaled.contact_dumps for rc in rendered):
        return []
    return [f"analysis.granules: {settings.granules}: its granules never beat a cohesionless "
            "control on the regime map (a CPM tiling / a bed-spanning cluster, in a twin without "
            "cohesion as in the wet bed; docs/results/granule_definitions.md); granules: held "
            "(hold_time about half a revolution) came closest: it beat the twin in share, "
            "co-movement and reproducibility, though not in survival"]
