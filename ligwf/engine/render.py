"""Rendering: a scaled scene in, LIGGGHTS input text out. No I/O.

``render(scaled)`` returns ``{file name: text}``; writing is a separate step (``cases``).
Templates are Jinja2 with StrictUndefined (a missing value is an error, not an empty
string) and are looked up through a ChoiceLoader: user folders first, then ligwf's own,
so a site can override one template without copying the rest.

Every value substituted into a template goes through :func:`_finalize`, which refuses
strings carrying a newline or other control character, '&', '$', '#' or a quote: no scene value can inject a
LIGGGHTS command (the engine has ``shell``).
"""

from __future__ import annotations

import math
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, Iterable, Sequence

import jinja2

from ligwf import __version__
from ligwf.errors import RenderError
from ligwf.liquids.contact_angle import input_angle
from ligwf.engine.decomposition import runner_grid
from ligwf.scene.scaled import ScaledScene, nested_name
from ligwf.scene.model import GRAVITY
from ligwf.scene.values import unsafe_chars
from ligwf.study.layout import INPUT_NAME, MESH_NAME


def shipped_template_dir() -> Path:
    """ligwf's own templates: inside the installed wheel, or the source tree's templates/."""
    packaged = resources.files("ligwf") / "templates"
    if packaged.is_dir():
        return Path(str(packaged))
    return Path(__file__).resolve().parents[2] / "templates"


def fmt_float(value: float) -> str:
    """Number as LIGGGHTS reads it: 12 significant digits (readable, far below any physical
    tolerance), no locale, never 'nan'/'inf'."""
    if isinstance(value, bool):
        raise RenderError(f"boolean {value!r} where a number is expected")
    if not math.isfinite(float(value)):
        raise RenderError(f"non-finite number {value!r} in a LIGGGHTS input")
    if isinstance(value, int):
        return str(value)
    return format(float(value), ".12g").replace("e+", "e")


def _finalize(value: Any) -> Any:
    if isinstance(value, str):
        bad = unsafe_chars(value)
        if bad:
            raise RenderError(f"refusing to render {value!r}: contains {bad!r}, which could "
                              "inject a LIGGGHTS command")
        return value
    if isinstance(value, float):
        return fmt_float(value)
    return value


@lru_cache(maxsize=16)
def _environment(user_dirs: tuple[str, ...]) -> jinja2.Environment:
    loaders = [jinja2.FileSystemLoader(d) for d in user_dirs]
    loaders.append(jinja2.FileSystemLoader(str(shipped_template_dir())))
    env = jinja2.Environment(
        loader=jinja2.ChoiceLoader(loaders),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        finalize=_finalize,
    )
    env.filters["num"] = fmt_float
    env.filters["vec"] = lambda xs: " ".join(fmt_float(x) for x in xs)
    return env


#: extra particles the last (top-up) insertion wave asks for and deletes again: covers the
#: per-rank rounding of an insertion (std ~ sqrt(ranks)/2, so 4 sigma at 64 ranks)
TOPUP_MARGIN = 16


def _unit(index: int, sign: float = 1.0) -> list[float]:
    v = [0.0, 0.0, 0.0]
    v[index] = sign
    return v


def template_context(s: ScaledScene) -> dict[str, Any]:
    """Everything the drum template needs, derived from the scaled scene (pure)."""
    ia, iu, iv = s.drum.axis.frame
    liquid = s.liquid_values
    r = s.drum.radius
    half_box = 1.05 * r + s.d_max
    lo = [-half_box] * 3
    hi = [half_box] * 3
    if s.drum.periodic:
        lo[ia], hi[ia] = 0.0, s.drum.length
    else:
        pad = 0.02 * s.drum.length + s.d_max
        lo[ia], hi[ia] = -pad, s.drum.length + pad
    boundary = ["f", "f", "f"]
    if s.drum.periodic:
        boundary[ia] = "p"
    # processor grid: never along gravity (the bed lies in the lower half: 96 % of a settled
    # bed on one of 2 ranks); ranks along the axis first, where the bed is uniform, then
    # across (a turning bed shifts to one side: 82/18 % on 2 ranks cut across, 1.4x slower
    # than cut along the axis, measured at CG1). The runner picks the numbers for its rank
    # count (processor_grid) and passes them with -var; run by hand, all ranks go along the axis.
    grid = ["1", "1", "1"]
    grid[ia], grid[iu] = "axial", "across"
    templates = [
        {"id": f"pts{k + 1}", "radius": 0.5 * d, "fraction": f, "seed": s.fill.seeds[k]}
        for k, (d, f) in enumerate(zip(s.particles.diameters, s.particles.number_fractions))
    ]
    k0 = len(templates)
    waves = [{"id": f"ins{k + 1}", "count": n, "seed": s.fill.seeds[k0 + 1 + k]}
             for k, n in enumerate(s.fill.waves)]
    return {
        "s": s,
        "version": __version__,
        "boundary": " ".join(boundary),
        "processor_grid": grid,
        "box_lo": lo,
        "box_hi": hi,
        "axis": s.drum.axis.value,
        "axial_lo": 0.0 if s.drum.periodic else 0.55 * s.d_max,
        "axial_hi": s.drum.length if s.drum.periodic else s.drum.length - 0.55 * s.d_max,
        "axis_vector": _unit(ia),
        "gravity": GRAVITY,
        "gravity_vector": _unit(iv, -1.0),
        "templates": templates,
        "distribution_seed": s.fill.seeds[k0],
        "waves": waves,
        "topup_margin": TOPUP_MARGIN,
        "rolling": s.particles.rolling_friction > 0.0,
        "wet": s.wet,
        # the liquid block comes from the case's model (ligwf.liquids): its cohesion
        # keyword, its lines (the contact angle as LIGGGHTS 3.8.0 needs it) and dump columns
        "cohesion": s.liquid.cohesion,
        # its on/off switches (washino's modifyLbVolume, limitLiquidContent), after all
        # the models of the pair style; none at the defaults
        "cohesion_settings": s.liquid.cohesion_settings(liquid),
        "liquid_lines": s.liquid.liggghts_lines(
            liquid, input_angle(liquid.contact_angle_deg, liquid.contact_angle_compensation)),
        "liquid_dump_columns": s.liquid.dump_columns,
        "mesh_name": MESH_NAME,
        "wet_spheres": [_xyz(ia, iu, iv, w) for w in liquid.wet_spheres],
    }


def _xyz(ia: int, iu: int, iv: int, sphere) -> dict:
    """A wet sphere (axial, across, vertical, radius) as box coordinates x, y, z, r."""
    xyz = [0.0, 0.0, 0.0]
    xyz[ia], xyz[iu], xyz[iv] = sphere[0], sphere[1], sphere[2]
    return {"x": xyz[0], "y": xyz[1], "z": xyz[2], "r": sphere[3]}


def processor_grid(s: ScaledScene, nprocs: int) -> tuple[int, int]:
    """Ranks (across the drum, along the axis) for ``nprocs``: the rank planner's grid
    (:func:`ligwf.engine.decomposition.runner_grid`: slabs along the axis of at least
    MIN_AXIAL_SLAB largest diameters, then columns across where they pay) (pure)."""
    if nprocs < 1:
        raise ValueError(f"nprocs = {nprocs}: need at least 1")
    axial, across = runner_grid(s, nprocs)
    return across, axial


def grid_vars(s: ScaledScene, nprocs: int) -> list[str]:
    """LIGGGHTS command-line arguments setting the processor grid of the drum template."""
    across, axial = processor_grid(s, nprocs)
    return ["-var", "ligwf_pu", str(across), "-var", "ligwf_pa", str(axial)]


def render_template(name: str, context: dict[str, Any],
                    template_dirs: Iterable[str | Path] = ()) -> str:
    """Render one named template (user folders first, then ligwf's) with ``context``."""
    env = _environment(tuple(str(Path(d)) for d in template_dirs))
    try:
        return env.get_template(name).render(**context)
    except jinja2.TemplateError as exc:
        raise RenderError(f"cannot render {name}: {exc}{flat_name_hint(str(exc))}") from exc
    except UnicodeDecodeError as exc:   # a user's template saved in another encoding
        raise RenderError(f"template {name} (searched in {', '.join(map(str, template_dirs))} "
                          f"before ligwf's own) is not UTF-8 text (byte {exc.object[exc.start]:#04x} "
                          f"at offset {exc.start}); save it as UTF-8") from None


def flat_name_hint(message: str) -> str:
    """For a user's template that asks the scaled scene for a name of its flat record
    (``s.dt``, ``s.youngs_modulus``, as templates did before the record was nested): where
    that value is now, so the error says how to mend the template."""
    found = re.search(r"ScaledScene object' has no attribute '(\w+)'", message)
    where = nested_name(found.group(1)) if found else None
    return f" (the scaled scene is nested: s.{found.group(1)} is s.{where})" if where else ""


def render(scaled: ScaledScene, template_dirs: Iterable[str | Path] = ()) -> dict[str, str]:
    """LIGGGHTS input files for one case: ``{file name: text}`` (pure, no I/O)."""
    return {INPUT_NAME: render_template("drum.in.j2", template_context(scaled), template_dirs)}


def render_bridge_probe(scaled: ScaledScene, gap_ratio: float, model_approach: bool,
                        template_dirs: Iterable[str | Path] = (),
                        velocity: tuple[float, float, float] = (0.0, 0.0, 0.0),
                        path: Sequence[float] = ()) -> dict[str, str]:
    """Input of a two-particle probe: two smallest particles of ``scaled`` held (no
    integrator) at surface gap ``gap_ratio * r_eff``; the thermo prints the force on
    particle 2 (``v_fx2``). With ``model_approach`` the pair touches first and is then
    separated, which the easo model needs to form its bridge. ``velocity`` (m/s) is given
    to particle 2 (particle 1 rests; positions stay put, but the engine's viscous force
    reads the velocities). ``path``: gap ratios particle 2 is then set to one after the
    other, one step each (a bridge's formation and rupture along a prescribed approach
    and separation).
    """
    ctx = template_context(scaled)
    radius = 0.5 * scaled.d_min
    ctx.update(probe_radius=radius, probe_gap=gap_ratio * 0.5 * radius, approach=model_approach,
               probe_velocity=tuple(float(v) for v in velocity),
               probe_path=[2 * radius + g * 0.5 * radius for g in path])
    return {INPUT_NAME: render_template("bridge_probe.in.j2", ctx, template_dirs)}
