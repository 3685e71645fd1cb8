"""The granule-growth study: every seed of a wet bed beside its control, judged by the
pre-registered criteria (docs/results/granule_growth/criterion.md), "k of n seeds" each.

:func:`measure_case` reads one run once and gives its growth rows
(:func:`ligwf.analysis.granules.growth.growth_rows`), the granule share at other window
cadences (is the definition invariant to how often the run dumped?) and the flow of its
frames (angle of repose: does the control flow like the wet bed?). :func:`seed_table` pairs
each wet seed with its control and evaluates every criterion per seed; :func:`verdict`
counts the seeds. The functions after :func:`measure_case` are pure (tables in, tables out).
:func:`measure_study` measures every run of a study folder into :class:`GrowthTables` (each
run's measures cached beside it, so runs done early can be measured while others still run:
:func:`measure_finished`); :func:`calibration_rounds` joins the rounds of
``ligwf calibrate-control``.
"""

from __future__ import annotations

from dataclasses import dataclass
from multiprocessing import Pool
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.flow.frame import DrumGeometry, frame_flow
from ligwf.analysis.granules.control_run import load_series
from ligwf.analysis.granules.controls import bed_share
from ligwf.analysis.granules.growth import (GrowthSettings, HeldAt, frames_spanning,
                                            growth_rows, hac_slope)
from ligwf.study.case import CaseFolder
from ligwf.study.layout import (CALIBRATION_TABLE, GROWTH_CACHE, PARTICLE_DUMP_RE, POST_DIR,
                                is_case_folder)


#: a particle carrying more liquid than this fraction of its volume counts as wet
WET = 1e-5


@dataclass(frozen=True)
class Criteria:
    """The pre-registered thresholds (criterion.md); a criterion passes in >= ``seeds_needed``
    of the seeds."""

    control_ratio: float = 0.2       # control share_10 <= this x the wet share_10
    min_share: float = 0.02          # the wet bed has granules at all
    survival: float = 0.5
    spanning_frames: float = 0.10    # at most this share of start frames with a spanning granule
    wall_ratio: float = 1.5          # granule wall share <= this x the bed's wall share
    comove_ratio: float = 0.5
    angle_match_deg: float = 1.0     # a control flows like the wet bed within this
    seeds_needed: int = 4


def measure_case(case_dir: Path, settings: GrowthSettings = GrowthSettings(),
                 cadences: tuple[float, ...] = (0.01, 0.02, 0.05),
                 flow_every: float = 0.05) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(growth rows, share_10 per start frame at each window cadence, flow per frame)."""
    case = CaseFolder.open(case_dir)
    series = load_series(case_dir)
    radius = 0.5 * float(case.scaled.drum.diameter)
    rows = growth_rows(series, settings, radius)
    volumes = series.frames[0].particles.volumes
    stride = frames_spanning(series, settings.stride)
    starts = [k for k in range(len(series.frames))
              if series.times[k] >= settings.start_after - 1e-9][::stride]
    shares = []
    for cadence in cadences:
        if abs(cadence / series.interval - round(cadence / series.interval)) > 1e-3:
            continue
        held = HeldAt(series, settings.hold_time, cadence)
        for k in starts:
            ident = held(k)
            if ident is None:
                break
            shares.append({"case_id": case.case_id, "cadence": cadence,
                           "time": float(series.times[k]),
                           "share_10": bed_share(ident.labels, volumes, settings.min_particles)})
    geo = DrumGeometry.from_scaled(case.scaled)
    flows = []
    for k in range(0, len(series.frames), frames_spanning(series, flow_every)):
        particles = series.frames[k].particles
        f = frame_flow(particles, geo)
        lc = particles.liquid_content
        flows.append({"case_id": case.case_id, "time": float(series.times[k]),
                      "angle_of_repose": f.angle_of_repose, "rigid_fraction": f.rigid_fraction,
                      # the liquid spreads: the engine passes it on when a bridge ruptures
                      "wet_share": float(np.mean(lc > WET)) if lc is not None else np.nan})
    return rows, pd.DataFrame(shares), pd.DataFrame(flows)


def _pairs(case_ids: list[str], suffix: str) -> list[tuple[str, str]]:
    """(wet case, its control) for every wet case with a ``<case>_<suffix>`` twin."""
    ids = set(case_ids)
    return [(c, f"{c}_{suffix}") for c in sorted(ids)
            if not c.endswith(f"_{suffix}") and f"{c}_{suffix}" in ids]


def seed_table(rows: pd.DataFrame, flows: pd.DataFrame, control: str = "cohesionless",
               criteria: Criteria = Criteria(), settings: GrowthSettings = GrowthSettings(),
               steady_after: float = 1.0) -> pd.DataFrame:
    """One row per wet seed: each measure of the wet bed and of its control, and whether
    each pre-registered criterion holds for that seed. ``steady_after`` (s): the flow
    (angle) is averaged after it."""
    lag = int(round(settings.hold_time / settings.stride)) + 1
    out = []
    for wet, twin in _pairs(sorted(rows["case_id"].unique()), control):
        w, c = rows[rows.case_id == wet], rows[rows.case_id == twin]
        fw = flows[(flows.case_id == wet) & (flows.time >= steady_after)]
        fc = flows[(flows.case_id == twin) & (flows.time >= steady_after)]
        slope = hac_slope(w["time"].to_numpy(), w["share_10"].to_numpy(), lag)
        twin_slope = hac_slope(c["time"].to_numpy(), c["share_10"].to_numpy(), lag)
        row = {
            "seed": wet, "control": twin,
            "share_10": w.share_10.mean(), "control_share_10": c.share_10.mean(),
            "share_10_first_rev": w[w.revolutions < 1.5].share_10.mean(),
            "share_10_last_rev": w[w.revolutions >= w.revolutions.max() - 1.0].share_10.mean(),
            "d50_particles": w.d50_particles.mean(),
            "d50_first_rev": w[w.revolutions < 1.5].d50_particles.mean(),
            "d50_last_rev": w[w.revolutions >= w.revolutions.max() - 1.0].d50_particles.mean(),
            "count_10": w.count_10.mean(), "control_count_10": c.count_10.mean(),
            "control_d50_particles": c.d50_particles.mean(),
            "survival": w.survival.mean(), "control_survival": c.survival.mean(),
            "slope_per_s": slope.slope, "slope_low": slope.low, "slope_high": slope.high,
            "control_slope_per_s": twin_slope.slope,
            "spanning_frames": w.spanning.astype(float).mean(),
            "control_spanning_frames": c.spanning.astype(float).mean(),
            "wall_share": w.wall_share.mean(), "bed_wall_share": w.bed_wall_share.mean(),
            "control_wall_share": c.wall_share.mean(),
            "comove_ratio": w.comove_ratio.mean(), "control_comove_ratio": c.comove_ratio.mean(),
            "accreted": w.accreted.sum(), "eroded": w.eroded.sum(),
            "broke": w.broke.sum(), "coalesced": w.coalesced.sum(),
            "dispersed": w.dispersed.sum(), "continued": w.continued.sum(),
            "born": w.born.sum(), "died": w.died.sum(),
            "wet_share_start": _at(flows[flows.case_id == wet], "wet_share", first=True),
            "wet_share_end": _at(flows[flows.case_id == wet], "wet_share", first=False),
            "angle_deg": fw.angle_of_repose.mean(), "control_angle_deg": fc.angle_of_repose.mean(),
            "angle_std_deg": fw.angle_of_repose.std(),
            "control_angle_std_deg": fc.angle_of_repose.std(),
            "start_frames": len(w), "revolutions": float(w.revolutions.max()) if len(w) else 0.0,
        }
        row.update(judge(row, criteria))
        out.append(row)
    return pd.DataFrame(out)


def _at(flow: pd.DataFrame, column: str, first: bool) -> float:
    """``column`` in the first (or last) frame of a run's flow rows (nan without rows or
    column)."""
    if column not in flow or flow.empty:
        return float("nan")
    row = flow.loc[flow["time"].idxmin() if first else flow["time"].idxmax()]
    return float(row[column])


def judge(row: dict, criteria: Criteria) -> dict[str, bool]:
    """Each pre-registered criterion for one seed (NaN measures fail: no evidence)."""
    def le(a, b):
        return bool(np.isfinite(a) and np.isfinite(b) and a <= b)

    share = row["share_10"]
    return {
        "pass_control": bool(share >= criteria.min_share
                             and le(row["control_share_10"], criteria.control_ratio * share)),
        "pass_survival": bool(np.isfinite(row["survival"]) and row["survival"] >= criteria.survival),
        "pass_growth": bool(np.isfinite(row["slope_low"]) and row["slope_low"] > 0.0),
        "pass_no_spanning": le(row["spanning_frames"], criteria.spanning_frames),
        "pass_not_wall": le(row["wall_share"], criteria.wall_ratio * row["bed_wall_share"]),
        "pass_comovement": le(row["comove_ratio"], criteria.comove_ratio),
        "flow_matched": le(abs(row["angle_deg"] - row["control_angle_deg"]),
                           criteria.angle_match_deg),
    }


#: criterion column -> what it says (the order of the verdict table)
CRITERIA = (
    ("pass_control", "granules exist (share_10 >= 0.02) and the control holds <= 1/5 of them"),
    ("pass_survival", "pairs still together a quarter revolution after the window (>= 0.5)"),
    ("pass_growth", "share_10 grows: the 95 % interval of its slope lies above 0"),
    ("pass_no_spanning", "no slice-spanning granule in >= 90 % of start frames"),
    ("pass_not_wall", "granule volume at the wall <= 1.5x the bed's own wall share"),
    ("pass_comovement", "members move together after the window (ratio <= 0.5)"),
)


def verdict(seeds: pd.DataFrame, criteria: Criteria = Criteria()) -> pd.DataFrame:
    """One row per criterion: seeds passing, seeds, and whether it passes (>= k of n); a
    last row says whether the control flowed like the wet bed, and one whether the regime
    passes (every criterion)."""
    n = len(seeds)
    rows = []
    for col, text in CRITERIA:
        k = int(seeds[col].sum()) if n else 0
        rows.append({"criterion": col.removeprefix("pass_"), "meaning": text, "seeds_pass": k,
                     "seeds": n, "passes": bool(n and k >= criteria.seeds_needed)})
    k = int(seeds["flow_matched"].sum()) if n else 0
    rows.append({"criterion": "flow_matched",
                 "meaning": "the control's angle of repose within 1 deg of the wet bed's",
                 "seeds_pass": k, "seeds": n, "passes": bool(n and k >= criteria.seeds_needed)})
    regime = bool(n) and all(r["passes"] for r in rows[:len(CRITERIA)])
    rows.append({"criterion": "regime", "meaning": "every granule criterion passes",
                 "seeds_pass": int(seeds[[c for c, _ in CRITERIA]].all(axis=1).sum()) if n else 0,
                 "seeds": n, "passes": regime})
    return pd.DataFrame(rows)


def cadence_table(shares: pd.DataFrame) -> pd.DataFrame:
    """Mean share_10 per case and window cadence, and the largest difference from the
    registered cadence's value (is the held definition invariant to the dump interval?)."""
    if shares.empty:
        return pd.DataFrame(columns=["case_id", "cadence", "share_10"])
    cadences = shares.cadence.nunique()
    common = shares.groupby(["case_id", "time"]).filter(lambda g: g.cadence.nunique() == cadences)
    return (common.groupby(["case_id", "cadence"], sort=True)["share_10"].mean()
            .reset_index())


@dataclass(frozen=True)
class GrowthTables:
    """What :func:`measure_study` measures: every start frame of every run (``rows``), the
    held share at each window cadence (``cadence``), the angle of repose per frame
    (``flow``), one row per wet seed beside its control (``seeds``), k of n seeds per
    criterion (``verdict``) and one row per run (``runs``)."""

    rows: pd.DataFrame
    cadence: pd.DataFrame
    flow: pd.DataFrame
    seeds: pd.DataFrame
    verdict: pd.DataFrame
    runs: pd.DataFrame


def measured(case_dir: Path) -> tuple[pd.DataFrame, ...]:
    """:func:`measure_case` of a run, cached beside it (``layout.GROWTH_CACHE``; a run
    measured while others still ran is not measured again)."""
    if all((case_dir / n).exists() for n in GROWTH_CACHE):
        return tuple(pd.read_pickle(case_dir / n) for n in GROWTH_CACHE)
    print(f"measuring {case_dir.name} ...", flush=True)
    tables = measure_case(case_dir)
    for n, t in zip(GROWTH_CACHE, tables):
        tmp = case_dir / (n + ".tmp")
        t.to_pickle(tmp)
        tmp.replace(case_dir / n)
    return tables


def run_table(run_dir: Path, case_ids: list[str]) -> pd.DataFrame:
    """One row per run: its particles, production [s], particle dumps and status."""
    rows = []
    for cid in case_ids:
        case = CaseFolder.open(run_dir / cid)
        m = case.manifest()
        post = run_dir / cid / POST_DIR
        rows.append({"case_id": cid, "particles": int(case.scaled.particles.count),
                     "production_s": round(case.scaled.numerics.run_steps
                                           * case.scaled.numerics.dt, 3),
                     "frames": sum(bool(PARTICLE_DUMP_RE.match(p.name)) for p in
                                   (post.iterdir() if post.is_dir() else ())),
                     "status": m.status if m is not None else "not run"})
    return pd.DataFrame(rows)


def measure_study(run_dir: Path, processes: int = 2) -> GrowthTables:
    """Every run of the study folder ``run_dir`` measured (``processes`` at a time, each
    cached beside its run), its seeds paired and judged."""
    case_ids = sorted(p.name for p in run_dir.iterdir() if is_case_folder(p))
    with Pool(processes) as pool:
        results = pool.map(measured, [run_dir / c for c in case_ids])
    rows, shares, flows = (pd.concat([r[i] for r in results], ignore_index=True)
                           for i in range(3))
    seeds = seed_table(rows, flows)
    return GrowthTables(rows, cadence_table(shares), flows, seeds, verdict(seeds),
                        run_table(run_dir, case_ids))


def measure_finished(run_dir: Path) -> None:
    """Measure (and cache) every run of ``run_dir`` that is done, one at a time: the
    study's runs can be measured while the last ones still run."""
    for p in sorted(run_dir.iterdir()):
        m = CaseFolder.open(p).manifest() if is_case_folder(p) else None
        if m is not None and m.status == "done":
            measured(p)


def calibration_rounds(folders: tuple[Path, ...]) -> pd.DataFrame:
    """The ``calibration.csv`` of each ``ligwf calibrate-control`` folder, in order (their
    ``round``: 1, 2, ...): the wet reference once, then every candidate."""
    cal = pd.concat([pd.read_csv(Path(c) / CALIBRATION_TABLE).assign(round=k + 1)
                     for k, c in enumerate(folders)], ignore_index=True)
    ref = cal[cal["role"] == "wet reference"].drop_duplicates("case_id")
    return pd.concat([ref, cal[cal["role"] == "candidate"]], ignore_index=True)
