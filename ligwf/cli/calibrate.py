"""Command line of the control calibration: ``ligwf calibrate-control``.

Runs short cohesionless candidates of a workflow's CG1 bed over a grid of friction and
rolling friction, measures their angle of repose against the wet bed's, and prints the
``sweep.flow_match`` of the candidate that flows most like it (with the distance left). The
chain is :mod:`ligwf.pipeline.calibrate`; this module parses and prints.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.table import Table

from ligwf.cli.common import (add_cores_arg, add_workflow_args, console, folder_to_write,
                              stop_on_signals)
from ligwf.engine.progress import RichMonitor
from ligwf.errors import ConfigError
from ligwf.pipeline.calibrate import CalibrationGrid, run_calibration
from ligwf.local import run_settings
from ligwf.scene.workflow import apply_override, parse_override
from ligwf.study.layout import CALIBRATION_TABLE, SCENE_FILE, is_case_folder
from ligwf.yamlio import read_yaml_mapping


def _values(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated numbers."""
    try:
        return tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: comma-separated numbers, e.g. "
                                         "0.5,0.8,1.0") from None


def _finished_case(text: str) -> Path:
    path = Path(text)
    if not is_case_folder(path):
        raise argparse.ArgumentTypeError(f"{text}: not a case folder (no {SCENE_FILE})")
    return path


def cmd_calibrate(args: argparse.Namespace) -> int:
    raw = read_yaml_mapping(args.workflow, "workflow file")
    for text in args.overrides:
        apply_override(raw, *parse_override(text))
    grid = CalibrationGrid(friction=args.friction, rolling_friction=args.rolling_friction,
                           run_time=args.run_time, tolerance_deg=args.tolerance)
    settings = run_settings(cores=args.cores, template_dirs=args.templates)
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        cal = run_calibration(raw, args.out, grid, settings, args.reference, monitor, stop,
                              args.allow_unstable)
    table = Table(title=f"flow-match calibration: {args.out / CALIBRATION_TABLE}")
    for col in ("role", "friction", "rolling friction", "angle [deg]", "angle std [deg]",
                "angle gap", "std gap", "chosen"):
        table.add_column(col, justify="left" if col == "role" else "right")
    for r in cal.table.itertuples():
        table.add_row(r.role, f"{r.friction:g}", f"{r.rolling_friction:g}",
                      f"{r.angle_deg:.2f}", f"{r.angle_std_deg:.2f}", f"{r.angle_gap_deg:+.2f}",
                      f"{r.std_gap_deg:+.2f}", "yes" if r.chosen else "")
    console.print(table)
    best = cal.chosen
    if best is None:
        raise ConfigError("calibrate-control: no candidate had a measurable angle of repose")
    fm = cal.flow_match()
    within = "within" if best.matched else "NOT within"
    console.print(f"sweep.flow_match: {{friction: {fm['friction']:g}, rolling_friction: "
                  f"{fm['rolling_friction']:g}}}  # angle {best.angle_gap_deg:+.2f} deg "
                  f"({within} {grid.tolerance_deg:g} deg), angle std {best.std_gap_deg:+.2f} "
                  "deg from the wet bed's", highlight=False, soft_wrap=True)
    return 0 if best.matched else 3


def register(subparsers) -> None:
    """Add ``calibrate-control`` to the ligwf command line."""
    p = subparsers.add_parser(
        "calibrate-control", help="find the friction and rolling friction with which the "
        "cohesionless twin of a wet CG1 bed flows like it (sweep.flow_match of a "
        "flow_matched control)")
    add_workflow_args(p)
    p.add_argument("--out", type=folder_to_write, required=True, help="calibration folder")
    p.add_argument("--friction", type=_values, default=(0.5, 0.8, 1.0), metavar="F1,F2,...",
                   help="candidate sliding friction coefficients (default 0.5,0.8,1.0)")
    p.add_argument("--rolling-friction", type=_values, default=(0.0, 0.3, 0.6),
                   metavar="R1,R2,...", help="candidate rolling friction coefficients "
                   "(default 0,0.3,0.6)")
    p.add_argument("--run-time", type=float, default=None, metavar="S",
                   help="seconds of production per run (default: the workflow's)")
    p.add_argument("--tolerance", type=float, default=1.0, metavar="DEG",
                   help="the wet angle of repose is matched within this (default 1 deg)")
    p.add_argument("--reference", type=_finished_case, default=None, metavar="CASE_DIR",
                   help="a finished wet CG1 case to match (default: run the wet bed too)")
    add_cores_arg(p)
    p.set_defaults(func=cmd_calibrate)
