"""Whether the production run leaves the held-granule analysis any frames, said before it runs.

``analysis.granules: held`` counts a bridge only when it is present in every frame of
``[t, t + hold_time]``, and the granule controls then follow each granule a quarter of a
revolution further (pair persistence at T/4). Both come out of the steady window, which starts
after the start-up the analysis leaves out: ``steady_after`` as a fraction, or with ``auto`` up
to :data:`AUTO_LATEST` of production (``ligwf.analysis.flow.steady`` bounds it there). The
gsd_cg study (docs/results/gsd_cg) lost its survival measure this way: the window started 1.2 s
into 2.5 s, a 1 s hold and a quarter revolution (0.5 s) did not fit. Warned, not refused: a
longer ``process.run_time`` or a shorter ``hold_time`` is the user's call.
"""

from __future__ import annotations

import math

from ligwf.scene.workflow import Workflow

#: the latest start of an automatic steady window, as a fraction of production
AUTO_LATEST = 0.5
#: fewer usable frames than this leave the block bootstrap and the survival measure nothing
MIN_USABLE_FRAMES = 10
#: a hold window must outlast the co-rotating plug by this factor: bridges of the plug hold
#: for as long as a particle rides it, in a bed without cohesion as in a wet one (issue 31:
#: ``held_0.5s`` held 13-15 % of the cohesionless twins of a drum whose plug lasts 0.8 s)
PLUG_MARGIN = 1.25
#: ... and be at most this many revolutions (longer windows leave little production)
MAX_HOLD_REVOLUTIONS = 1.0


def plug_arc(fill_fraction: float) -> float:
    """The angle (rad) of shell a bed of ``fill_fraction`` of the drum's cross-section covers
    at rest: the circular segment of that area, (theta - sin theta) / (2 pi) = fill (pure)."""
    if not 0.0 < fill_fraction < 1.0:
        raise ValueError(f"fill_fraction = {fill_fraction!r}: must lie in (0, 1)")
    lo, hi = 0.0, 2.0 * math.pi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (mid - math.sin(mid)) / (2.0 * math.pi) < fill_fraction:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def plug_residence(fill_fraction: float, period: float) -> float:
    """Seconds a particle rides the co-rotating plug: the shell arc under the bed over the
    drum's angular speed (``period`` s per revolution; pure)."""
    return plug_arc(fill_fraction) / (2.0 * math.pi) * period


def held_window_warnings(wf: Workflow) -> list[str]:
    """One warning per distinct (run time, speed, dump interval) whose held-granule window is
    too short: production - steady start - hold_time - T/4 holds fewer than
    :data:`MIN_USABLE_FRAMES` dump intervals, then those of :func:`hold_period_warnings`
    (pure)."""
    settings = wf.analysis
    if settings.granules != "held":
        return []
    start = AUTO_LATEST if settings.steady_after == "auto" else float(settings.steady_after)
    out: dict[tuple[float, float, float], str] = {}
    for case, period in _granule_cases(wf):
        run, every = case.scene.process.run_time, case.scene.numerics.dump_interval
        usable = run * (1.0 - start) - settings.hold_time - period / 4.0
        frames = math.floor(max(usable, 0.0) / every + 1e-9)
        key = (run, period, every)
        if frames < MIN_USABLE_FRAMES and key not in out:
            how = ("an automatic steady window may start as late as "
                   f"{AUTO_LATEST:.0%} of production" if settings.steady_after == "auto"
                   else f"steady_after = {start:g} of production")
            out[key] = (f"analysis.hold_time = {settings.hold_time:g} s: with "
                        f"process.run_time = {run:g} s ({how}) and a quarter revolution "
                        f"({period / 4.0:.3g} s) to follow the held granules, {frames} of the "
                        f"{MIN_USABLE_FRAMES} dump intervals the granule survival needs are left "
                        f"({case.case_id}); lengthen process.run_time to at least "
                        f"{(settings.hold_time + period / 4.0 + MIN_USABLE_FRAMES * every) / (1.0 - start):.3g} s "
                        "or shorten analysis.hold_time")
    return list(out.values()) + hold_period_warnings(wf)


def hold_period_warnings(wf: Workflow) -> list[str]:
    """One warning per (speed, fill) at which ``hold_time`` does not outlast the co-rotating
    plug by :data:`PLUG_MARGIN` (bridges of a bed turning with the drum then count as held
    granules, in a cohesionless twin too) or exceeds :data:`MAX_HOLD_REVOLUTIONS` (pure)."""
    settings = wf.analysis
    out: dict[tuple[float, float], str] = {}
    for case, period in _granule_cases(wf):
        fill = case.scene.process.fill_fraction
        plug = plug_residence(fill, period)
        lo, hi = PLUG_MARGIN * plug, MAX_HOLD_REVOLUTIONS * period
        key = (period, fill)
        if not lo <= settings.hold_time <= hi and key not in out:
            why = (f"the co-rotating plug holds its bridges for {plug:.3g} s "
                   f"({math.degrees(plug_arc(fill)):.0f} deg of shell at fill {fill:g}, "
                   f"period {period:.3g} s, {case.case_id}), so a shorter window counts the "
                   "plug as granules" if settings.hold_time < lo else
                   f"it is more than {MAX_HOLD_REVOLUTIONS:g} revolution of this drum "
                   f"(period {period:.3g} s, {case.case_id})")
            out[key] = (f"analysis.hold_time = {settings.hold_time:g} s: {why}; use "
                        f"analysis.hold_time = {min(lo, hi):.3g} s (allowed without warning: "
                        f"{lo:.3g}-{hi:.3g} s)")
    return list(out.values())


def _granule_cases(wf: Workflow):
    """(case, rotation period s) of every case whose granules are analysed (contact dumps
    on, a wet liquid)."""
    for case in wf.cases:
        scene = case.scene
        if scene.analysis.contact_dumps and scene.liquid.wet:
            yield case, 2.0 * math.pi / scene.process.rotation.omega(scene.drum.diameter / 2.0)
