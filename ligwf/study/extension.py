"""A case's production extension: more production than rendered, continued from restarts.

A sequential study (``ligwf study --until-decided``, :mod:`ligwf.pipeline.rounds`) may
decide that the cheapest way to narrow an interval is a longer production on the runs
there are. The scene record and its content hash stay exactly as rendered (an extension is
not a changed scene: the runner must continue the run, not start it afresh); the case
folder gets :data:`~ligwf.study.layout.EXTENSION_FILE` naming the rendered production
steps it extends and the new total. :class:`~ligwf.study.case.CaseFolder` adds the steps
to its scaled scene, so the runner (which continues a done case whose steps fall short
from its newest own restart, :func:`ligwf.engine.resume.plan_case`), the health checks,
the expected dumps and the analysis all see one longer run with one manifest, one thermo
table and one frame series.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json
from ligwf.scene.scaled import ScaledScene
from ligwf.study.layout import EXTENSION_FILE


def extension_steps(path: Path, scaled: ScaledScene) -> int:
    """Production steps added to the rendered run of the case folder ``path`` (0: none).
    The record names the rendered production it extends: one written for another scene
    (re-rendered with another run time since) is stale and ignored."""
    try:
        rec = json.loads((Path(path) / EXTENSION_FILE).read_text())
        base, target = int(rec["base_run_steps"]), int(rec["run_steps"])
    except FileNotFoundError:
        return 0
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ConfigError(f"{Path(path) / EXTENSION_FILE}: unreadable production extension "
                          f"({type(exc).__name__}: {exc})") from None
    return target - base if base == scaled.numerics.run_steps and target > base else 0


def write_extension(path: Path, base_run_steps: int, run_steps: int, dt: float) -> None:
    """Record that the case's production runs to ``run_steps`` instead of the rendered
    ``base_run_steps`` (atomically; the runner continues it from its restarts)."""
    atomic_write_json(Path(path) / EXTENSION_FILE, {
        "base_run_steps": int(base_run_steps), "run_steps": int(run_steps),
        "added_seconds": (int(run_steps) - int(base_run_steps)) * dt})


def extend_production(cases, seconds: float) -> list[str]:
    """Give every case of ``cases`` (:class:`~ligwf.study.case.CaseFolder`) a production
    ``seconds`` longer than rendered (``ligwf run --extend-production``: the fix the verdict
    names for runs too short to show a steady state). A case already extended as far or
    further (by an earlier call or a round) is left as it is, so repeating the call changes
    nothing; a done case is continued from its restarts by the next run, not re-run. One
    line per case extended."""
    lines = []
    for case in cases:
        rendered = case.rendered_scaled.numerics
        target = rendered.run_steps + math.ceil(seconds / rendered.dt)
        if target > case.scaled.numerics.run_steps:
            write_extension(case.path, rendered.run_steps, target, rendered.dt)
            lines.append(f"{case.path.name}: production extended to {target} steps "
                         f"(+{(target - rendered.run_steps) * rendered.dt:.3g} s)")
    return lines
