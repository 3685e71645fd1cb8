"""Calibrating a flow-matched control: which friction and rolling friction make the
cohesionless twin of a wet bed flow like it?

A granule control must lack only the wet bed's cohesion (issue 31): a cohesionless twin that
flows at another angle differs in flow too, and any measure that separates the two may be
measuring the flow. :func:`run_calibration` runs short CG1 candidates of the twin (surface
tension and viscosity / 1000, every combination of the given friction and rolling friction),
measures the angle of repose of each over its production after the spin-up, and compares it
with the wet bed's (a case already run, or a short run of the wet reference it makes). It
chooses the candidate within ``tolerance_deg`` of the wet angle whose angle fluctuation is
closest to the wet bed's (a slumping wet bed fluctuates more than any dry one measured so far:
the distance left is reported, never hidden), else the closest angle. The result is
``calibration.csv`` in the output folder and the ``sweep.flow_match`` a workflow then uses
with ``sweep.controls: [flow_matched]``.
"""

from __future__ import annotations

import copy
import math
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from ligwf.analysis.flow.stage import case_flow
from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepare
from ligwf.local import RunSettings
from ligwf.pipeline.run import start_run
from ligwf.scene.controls import COHESIONLESS_FACTOR
from ligwf.scene.workflow import expand
from ligwf.study.case import CaseFolder
from ligwf.study.layout import (CALIBRATION_CANDIDATES_DIR, CALIBRATION_REFERENCE_DIR,
                                CALIBRATION_TABLE)

#: the share of each calibration run's production left out as spin-up
SPIN_UP = 0.3
#: file of the measured candidates in the calibration folder


@dataclass(frozen=True)
class CalibrationGrid:
    """The candidates and how they are judged."""

    friction: tuple[float, ...] = (0.5, 0.8, 1.0)
    rolling_friction: tuple[float, ...] = (0.0, 0.3, 0.6)
    run_time: float | None = None       # s of production per run (None: the workflow's)
    tolerance_deg: float = 1.0          # the wet angle is matched within this

    def __post_init__(self) -> None:
        for name in ("friction", "rolling_friction"):
            values = getattr(self, name)
            if not values or any(not (isinstance(v, (int, float)) and 0.0 <= v <= 10.0)
                                 for v in values):
                raise ConfigError(f"calibrate-control --{name.replace('_', '-')} = "
                                  f"{list(values)}: one or more values in [0, 10]")
        if self.run_time is not None and not (math.isfinite(self.run_time)
                                              and 0.0 < self.run_time <= 1e3):
            raise ConfigError(f"calibrate-control --run-time = {self.run_time!r}: a time in "
                              "(0, 1000] s")
        if not (math.isfinite(self.tolerance_deg) and 0.0 < self.tolerance_deg <= 45.0):
            raise ConfigError(f"calibrate-control --tolerance = {self.tolerance_deg!r}: an "
                              "angle in (0, 45] deg")


def _base(raw: dict[str, Any], grid: CalibrationGrid, tag: str) -> dict[str, Any]:
    """The workflow's scene at CG1, one seed, no controls, the calibration's run time."""
    out = {k: copy.deepcopy(v) for k, v in raw.items() if k in ("scene", "analysis")}
    out["name"] = f"{raw.get('name', 'study')}-{tag}"
    out["description"] = f"flow-match calibration ({tag}) of {raw.get('name', 'study')}"
    out["sweep"] = {"cg_levels": [1], "rules": ["weber"], "replicas": 1}
    if grid.run_time is not None:
        out["scene"].setdefault("process", {})["run_time"] = grid.run_time
    return out


def calibration_workflows(raw: dict[str, Any], grid: CalibrationGrid
                          ) -> tuple[dict[str, Any], dict[str, Any]]:
    """(wet reference, cohesionless candidates): raw workflows of the calibration (pure)."""
    reference = _base(raw, grid, "wet")
    candidates = _base(raw, grid, "candidates")
    liquid = candidates["scene"].setdefault("liquid", {})
    if not liquid or liquid.get("model", "none") == "none":
        raise ConfigError("calibrate-control: the workflow's scene is dry (liquid.model none): "
                          "it is its own cohesionless control, there is no wet flow to match")
    for key in ("surface_tension", "viscosity"):
        if key in liquid:
            liquid[key] = float(liquid[key]) * COHESIONLESS_FACTOR
    liquid.setdefault("surface_tension", 0.072 * COHESIONLESS_FACTOR)
    liquid.setdefault("viscosity", 1e-3 * COHESIONLESS_FACTOR)
    candidates["sweep"]["scene.particles.friction"] = list(grid.friction)
    candidates["sweep"]["scene.particles.rolling_friction"] = list(grid.rolling_friction)
    return reference, candidates


def angle_of(case_dir: Path) -> dict[str, float]:
    """Angle of repose (mean and std over the production after :data:`SPIN_UP`, deg) of a
    finished case, with its friction values."""
    case = CaseFolder.open(case_dir)
    flow, _ = case_flow(case, SPIN_UP)
    p = case.scaled.particles
    return {"case_id": case.case_id, "friction": float(p.friction),
            "rolling_friction": float(p.rolling_friction),
            "angle_deg": float(flow.values.get("angle_of_repose", math.nan)),
            "angle_std_deg": float(flow.values.get("angle_of_repose_std", math.nan)),
            "frames": len(flow.series.get("angle", []))}


def choose(reference: dict[str, float], candidates: pd.DataFrame,
           tolerance_deg: float) -> pd.DataFrame:
    """The candidates with their distance to the wet bed and the chosen one marked (pure):
    within ``tolerance_deg`` of its angle the closest angle fluctuation, else the closest
    angle."""
    out = candidates.copy()
    out["angle_gap_deg"] = out["angle_deg"] - reference["angle_deg"]
    out["std_gap_deg"] = out["angle_std_deg"] - reference["angle_std_deg"]
    out["matched"] = out["angle_gap_deg"].abs() <= tolerance_deg
    pool = out[out["matched"]]
    key = "std_gap_deg" if len(pool) else "angle_gap_deg"
    pool = pool if len(pool) else out
    pick = pool[key].abs().idxmin() if pool[key].notna().any() else None
    out["chosen"] = out.index == pick
    return out


@dataclass(frozen=True)
class Calibration:
    """The calibration's table (reference row first) and its choice."""

    table: pd.DataFrame

    @property
    def chosen(self) -> pd.Series | None:
        rows = self.table[self.table["chosen"].astype(bool)]
        return rows.iloc[0] if len(rows) else None

    def flow_match(self) -> dict[str, float]:
        row = self.chosen
        if row is None:
            raise ConfigError("calibrate-control: no candidate had a measurable angle of repose")
        return {"friction": float(row["friction"]),
                "rolling_friction": float(row["rolling_friction"])}


def _run(raw: dict[str, Any], out: Path, settings: RunSettings, monitor, stop,
         allow_unstable: bool) -> list[Path]:
    prepared = prepare(expand(raw), settings.template_dirs, allow_unstable)
    # the calibration folder's two studies are its own: another grid or workflow replaces
    # them (cases it does not change keep their runs), as a calibration run again expects
    run = start_run(prepared, out, settings, replace=True)
    if not run.run(monitor, stop):
        bad = [c.case_id for c in run.study.cases
               if (m := c.manifest()) is None or m.status != "done"]
        raise ConfigError(f"calibrate-control: calibration run(s) not done: {', '.join(bad)} "
                          f"(see {out}); run the same command again to resume")
    return [c.path for c in run.study.cases]


def run_calibration(raw: dict[str, Any], out: Path, grid: CalibrationGrid,
                    settings: RunSettings, reference_case: Path | None = None,
                    monitor=None, stop: threading.Event | None = None,
                    allow_unstable: bool = False) -> Calibration:
    """Run (or resume) the candidates, and the wet reference unless ``reference_case`` (a
    finished wet CG1 case) is given; measure, choose, write ``calibration.csv`` atomically."""
    from ligwf.fsio import atomic_write_text

    ref_raw, cand_raw = calibration_workflows(raw, grid)
    if reference_case is None:
        (reference_case,) = _run(ref_raw, out / CALIBRATION_REFERENCE_DIR, settings, monitor, stop, allow_unstable)
    ref = angle_of(reference_case) | {"role": "wet reference"}
    cands = pd.DataFrame([angle_of(p) | {"role": "candidate"}
                          for p in _run(cand_raw, out / CALIBRATION_CANDIDATES_DIR, settings, monitor, stop,
                                        allow_unstable)])
    table = choose(ref, cands, grid.tolerance_deg)
    ref_row = pd.DataFrame([ref | {"angle_gap_deg": 0.0, "std_gap_deg": 0.0,
                                   "matched": True, "chosen": False}])
    table = pd.concat([ref_row, table], ignore_index=True)
    atomic_write_text(out / CALIBRATION_TABLE, table.to_csv(index=False, float_format="%.6g"))
    return Calibration(table)
