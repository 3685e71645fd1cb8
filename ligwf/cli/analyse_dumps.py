"""``ligwf analyse-dumps DIR``: granules and GSD of LIGGGHTS dumps ligwf did not write.

Dumps from a hand-written input carry no scene record, so everything the bond criterion
and the periodic unwrapping need is given here, and every piece is required (nothing
defaults silently: a missing box length would switch off the detection of granules that
wrap around the periodic axis). The dumps must be ``dump custom/vtk`` particle files
with the arrays id, type, v, radius (and f_surfaceLiquidContent, else give
--liquid-content) and ``dump local/gran/vtk`` contact files with id1, id2, delta (see
README "Analysing foreign dumps"). A liquid model's own settings (washino's
``--bridge-volume-fraction``, ...) are one option each, made from the models' settings
classes. Outputs are those of ``ligwf analyse``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ligwf import liquids
from ligwf.cli.analyse import print_record
from ligwf.cli.common import folder_to_write, number_in, step_number
from ligwf.liquids.base import MAX_LIQUID_CONTENT
from ligwf.scene.axis import Axis
from ligwf.study import layout

#: the namespace attribute of a liquid model's setting given as an option
SETTING_DEST = "liquid_setting_{}"


def finite_number(text: str) -> float:
    """argparse type: a finite number (the liquid model's settings class checks its range)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


def register(subparsers) -> None:
    """Add the ``analyse-dumps`` sub-command."""
    p = subparsers.add_parser(
        "analyse-dumps", help="granules and GSD of LIGGGHTS dumps ligwf did not write",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dump_dir", type=Path, help="folder with the particle and contact dumps")
    p.add_argument("--out", type=folder_to_write, default=None,
                   help="output folder (default DIR/analysis)")
    p.add_argument("--liquid", required=True, choices=liquids.names(), help="liquid model")
    p.add_argument("--surface-tension", type=number_in(1e-6, 1e4, "N/m"),
                   help="N/m as the engine used it (CG-scaled); required for a wet model")
    p.add_argument("--contact-angle", type=number_in(0.0, 180.0, "deg"),
                   help="deg; required for a wet model")
    p.add_argument("--angle-convention", required=True, choices=("engine", "scene"),
                   help="engine: the value written into a LIGGGHTS 3.8.0 input (which applied "
                   "0.5 theta^2); scene: the angle the engine applied (fixed engine)")
    p.add_argument("--periodic-axis", required=True, choices=[*(a.value for a in Axis), "none"])
    p.add_argument("--box-length", type=number_in(1e-6, 10.0, "m"), help="m, length of the periodic box "
                   "(it spans [0, L]); required with a periodic axis")
    p.add_argument("--dt", type=number_in(1e-10, 1.0, "s"), required=True,
                   help="time step, s")
    p.add_argument("--liquid-content", type=number_in(1e-5, MAX_LIQUID_CONTENT),
                   default=None,
                   help="fraction of particle volume, when the dumps lack f_surfaceLiquidContent")
    for key, models in liquids.setting_owners().items():
        info = next(liquids.get(m).settings_type.model_fields[key] for m in models)
        p.add_argument("--" + key.replace("_", "-"), dest=SETTING_DEST.format(key),
                       metavar=key.upper(), type=finite_number, default=None,
                       help=f"the run's liquid.{key}: {info.description}")
    p.add_argument("--cg", type=number_in(1.0, 1000.0), default=1.0,
                   help="coarse-graining factor of the run")
    p.add_argument("--steady-from-step", type=step_number, default=0,
                   help="first step of the GSD window (default: every frame)")
    p.add_argument("--particles", default=layout.PARTICLE_DUMP_GLOB, help="particle file pattern")
    p.add_argument("--contacts", default=layout.CONTACT_DUMP_GLOB, help="contact file pattern")
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="KEY=VALUE",
                   help="an analysis setting, e.g. max_velocity_angle=10 (repeatable)")
    p.add_argument("--no-vtu", action="store_true", help="do not write the .pvd/.vtu series")
    p.set_defaults(func=cmd_analyse_dumps)


def cmd_analyse_dumps(args: argparse.Namespace) -> int:
    from ligwf.analysis.foreign import ForeignRun, analyse_dumps
    from ligwf.errors import ConfigError
    from ligwf.scene.settings import build_analysis_settings
    from ligwf.yamlio import parse_yaml

    values = {}
    for item in args.settings:
        key, sep, value = item.partition("=")
        if not sep:
            raise ConfigError(f"--set {item!r}: use KEY=VALUE")
        if not key.strip():
            raise ConfigError(f"--set {item!r}: empty key")
        values[key.strip()] = parse_yaml(value, f"--set {key.strip()}: value {value!r}")
    settings = build_analysis_settings(values, "analysis")
    own = {key: getattr(args, SETTING_DEST.format(key)) for key in liquids.setting_owners()
           if getattr(args, SETTING_DEST.format(key)) is not None}
    run = ForeignRun(args.liquid, args.surface_tension, args.contact_angle,
                     args.angle_convention, args.periodic_axis, args.box_length, args.dt,
                     args.liquid_content, args.cg, own)
    out = args.out or args.dump_dir / layout.ANALYSIS_DIR
    record = analyse_dumps(args.dump_dir, run, out, settings, args.steady_from_step,
                           args.particles, args.contacts, not args.no_vtu)
    print_record(record, out)
    return 0
