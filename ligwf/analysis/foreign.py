"""Granules of LIGGGHTS dumps ligwf did not write (``ligwf analyse-dumps``).

A ligwf case carries everything the granule analysis needs in its scene record; dumps
from a hand-written input carry none of it. :class:`ForeignRun` is what the user must
state instead -- the liquid model and its CG-scaled surface tension, the contact angle
and which convention it is in, the periodic axis and its length, the time step -- and
every piece is required: a missing time step would put every frame at time 0, a missing
box length would silently switch off the detection of granules that wrap around the
periodic axis. Frames are found by file-name patterns (``*`` stands for the step), read
and checked like a ligwf case's (structure, nan, duplicate ids, contact geometry against
the particles); they cannot be checked against a scene (count, radii, drum) or a dump
record, which the analysis record says. Outputs are the granule outputs of ``ligwf
analyse`` written by the same stage (:func:`ligwf.analysis.granule_stage.stage_granules`:
granule, frame, GSD, pooling, kinetics and sensitivity tables, the granule series), as one
set; the GSD, pooling and sensitivity use the frames from ``steady_from_step`` on. The
flow metrics (they need the drum) and the controls (no twin) are the two outputs a
foreign run cannot have: the record says so.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ligwf import liquids
from ligwf.analysis.granules.case import GranuleAnalysis, RunFacts
from ligwf.analysis.frames.dumps import FrameFiles, read_particles
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.granule_stage import (GRANULE_OUTPUTS, frame_tables,
                                          nothing_analysed, stage_granules)
from ligwf.analysis.granules.bridge_law import Liquid
from ligwf.analysis.outputs import OutputSet, new_token
from ligwf.liquids.contact_angle import applied_contact_angle_rad
from ligwf.errors import ConfigError, DumpReadError
from ligwf.liquids.base import LiquidModel, LiquidSettings
from ligwf.scene.axis import Axis
from ligwf.scene.messages import range_note
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout

#: ``engine``: the angle as written into a LIGGGHTS 3.8.0 input (the engine applied
#: 0.5 theta^2, see :mod:`ligwf.liquids.contact_angle`); ``scene``: the angle the engine applied
#: (an engine with the upstream fix, or an input compensated as ligwf does).
ANGLE_CONVENTIONS = ("engine", "scene")
#: what the record says of the two outputs of ``ligwf analyse`` a foreign run cannot have
NO_FLOW = ("not measured: the flow metrics and the cross-section flow fields need the drum "
           "(radius, axis, rotation), which foreign dumps do not state")
NO_CONTROLS = "none: a foreign run has no cohesionless twin"


@dataclass(frozen=True)
class ForeignCase:
    """A foreign run seen as a case of the GSD tables (one condition, one replica)."""

    case_id: str
    cg: float
    rule: str = "foreign"
    replica: int = 0
    group: str = ""


@dataclass(frozen=True)
class ForeignRun:
    """Everything the granule analysis needs about a run ligwf did not write."""

    liquid: str                      # a ligwf liquid model name (ligwf.liquids)
    surface_tension: float | None    # N/m as the engine used it (CG-scaled); None: dry
    contact_angle_deg: float | None
    angle_convention: str            # one of ANGLE_CONVENTIONS
    periodic_axis: str               # x, y, z, or "none"
    box_length: float | None         # m, the periodic length (box [0, L] on that axis)
    dt: float                        # s per step
    liquid_content: float | None = None   # fraction of particle volume, if dumps lack it
    cg: float = 1.0
    #: the liquid model's own settings in the run, by key (e.g. washino's
    #: ``bridge_volume_fraction``: its lbVolumeFraction); unset: the model's defaults
    settings: dict[str, Any] = field(default_factory=dict)

    def facts(self, name: str) -> RunFacts:
        """The run facts; ConfigError naming the missing or invalid piece."""
        try:
            law = liquids.get(self.liquid)
        except ValueError as exc:
            raise ConfigError(f"--liquid: {exc}") from None
        if self.angle_convention not in ANGLE_CONVENTIONS:
            raise ConfigError(f"--angle-convention {self.angle_convention!r}: use "
                              f"{' or '.join(ANGLE_CONVENTIONS)}")
        gamma = theta = 0.0
        if law.wet:
            if self.surface_tension is None or not self.surface_tension > 0:
                raise ConfigError(f"--surface-tension: a wet model ({self.liquid}) needs the "
                                  "surface tension the engine used, N/m (> 0)")
            if self.contact_angle_deg is None or not 0 <= self.contact_angle_deg < 90:
                raise ConfigError("--contact-angle: a wet model needs the contact angle, "
                                  "deg, in [0, 90)")
            gamma = float(self.surface_tension)
            theta = applied_contact_angle_rad(self.contact_angle_deg,
                                              compensated=self.angle_convention == "scene")
        try:
            axis = None if self.periodic_axis == "none" else Axis(self.periodic_axis)
        except ValueError:
            raise ConfigError(f"--periodic-axis {self.periodic_axis!r}: use x, y, z or "
                              "none") from None
        if axis is not None and (self.box_length is None or not self.box_length > 0):
            raise ConfigError(f"--box-length: a periodic axis ({axis}) needs its length, m (> 0)")
        if not (self.dt > 0 and math.isfinite(self.dt)):
            raise ConfigError(f"--dt {self.dt!r}: the time step must be > 0 s")
        content = math.nan if self.liquid_content is None else float(self.liquid_content)
        return RunFacts(name, float(self.cg),
                        Liquid(self.liquid, gamma, theta, content, self.model_settings(law)),
                        axis,
                        float(self.box_length or 0.0), float(self.dt))

    def model_settings(self, law: LiquidModel) -> LiquidSettings:
        """``settings`` validated by the model's own settings class; ConfigError naming the
        option (``--<key>``), its value and the allowed range."""
        def option(key: str) -> str:
            return "--" + key.replace("_", "-")

        for key, value in self.settings.items():
            if key not in law.settings_type.model_fields:
                owners = liquids.setting_owners().get(key)
                raise ConfigError(f"{option(key)} {value!r}: liquid model {self.liquid!r} has "
                                  "no such setting" + (f" ({', '.join(owners)} only)"
                                                       if owners else ""))
        try:
            return law.settings_type.model_validate(self.settings)
        except ValidationError as exc:
            e = exc.errors()[0]
            raise ConfigError(f"{option(e['loc'][0])} {e['input']!r}: {e['msg']}" + range_note(
                law.settings_type, e["loc"], e["msg"], e["type"])) from None


def find_frames(dump_dir: Path, particles: str, contacts: str) -> list[FrameFiles]:
    """Frames in ``dump_dir`` by file-name patterns (``*`` = the step); ConfigError when
    there is none or a pattern has no ``*``."""
    def regex(pattern: str) -> re.Pattern:
        if pattern.count("*") != 1:
            raise ConfigError(f"file pattern {pattern!r}: needs exactly one * for the step")
        head, tail = pattern.split("*")
        return re.compile("^" + re.escape(head) + r"(\d+)" + re.escape(tail) + "$")
    dump_dir = Path(dump_dir)
    if not dump_dir.is_dir():
        raise ConfigError(f"{dump_dir}: no such folder")
    found: dict[str, dict[int, Path]] = {"p": {}, "c": {}}
    for key, rx in (("p", regex(particles)), ("c", regex(contacts))):
        for path in sorted(dump_dir.iterdir()):
            if m := rx.match(path.name):
                step = int(m.group(1))
                if step in found[key]:
                    # particles_100.vtu and particles_0100.vtu: one frame twice, or two
                    # runs' dumps in one folder; taking either would be a silent guess
                    raise ConfigError(f"{dump_dir}: {found[key][step].name} and {path.name} "
                                      f"are both step {step}; keep one dump per step (or "
                                      "narrow --particles / --contacts)")
                found[key][step] = path
    if not found["p"]:
        raise ConfigError(f"{dump_dir}: no particle dump named {particles}")
    return [FrameFiles(s, found["p"][s], found["c"].get(s)) for s in sorted(found["p"])]


def check_window(frames: list[FrameFiles], dt: float, settings: AnalysisSettings,
                 steady_from_step: int) -> None:
    """Refuse, naming the window, a GSD window after the last frame and a ``held`` hold
    window longer than the dumps (no frame could be analysed: every one would be skipped)."""
    first, last = frames[0].step, frames[-1].step
    if steady_from_step > last:
        raise ConfigError(f"--steady-from-step = {steady_from_step}: after the last frame "
                          f"(step {last}); allowed range [0, {last}]")
    span = (last - first) * dt
    if settings.granules == "held" and span < settings.hold_time:
        raise ConfigError(
            f"analysis.hold_time = {settings.hold_time:g} s: the dumps span {span:.3g} s "
            f"(steps {first}-{last} at --dt {dt:g} s), so no frame has a whole hold window "
            f"[t, t + hold_time] for granules: held; --set hold_time=VALUE below {span:.3g} s "
            "or --set granules=communities")


def analyse_dumps(dump_dir: Path, run: ForeignRun, out_dir: Path,
                  settings: AnalysisSettings = AnalysisSettings(), steady_from_step: int = 0,
                  particles: str = layout.PARTICLE_DUMP_GLOB,
                  contacts: str = layout.CONTACT_DUMP_GLOB,
                  write_vtu: bool = True) -> dict:
    """Analyse the frames of ``dump_dir``; write the outputs as one set into ``out_dir``
    and return the analysis record (NothingAnalysed, outputs untouched, when no frame
    could be analysed)."""
    dump_dir = Path(dump_dir)
    facts = run.facts(dump_dir.resolve().name)
    frames = find_frames(dump_dir, particles, contacts)
    check_window(frames, run.dt, settings, steady_from_step)
    if run.liquid_content is None and liquids.get(run.liquid).wet:
        try:
            lacks = read_particles(frames[0].particles, frames[0].step).liquid_content is None
        except DumpReadError:
            lacks = False                   # that frame is reported as unreadable below
        if lacks:
            raise ConfigError(f"--liquid-content: {frames[0].particles.name} has no "
                              "f_surfaceLiquidContent array; give the liquid content (fraction "
                              "of particle volume)")
    outputs = OutputSet(Path(out_dir), new_token())
    try:
        ana = GranuleAnalysis(facts, settings,
                              vtu_dir=outputs.case_dir(facts.case_id) if write_vtu else None)
        tables = frame_tables([facts], ana.run(frames).results)
        index, skipped = tables.frame_index, tables.skipped_frames
        if not index:
            raise nothing_analysed(dump_dir, [], skipped)
        stage_granules(outputs, tables, [facts], [ForeignCase(facts.case_id, facts.cg)],
                       {facts.case_id: float(steady_from_step)}, settings, "fast", write_vtu,
                       controls=False,
                       frames_of={facts.case_id: frames})
        run_record = asdict(run)
        # the model's settings as keys of the run, each left out when unset (records at
        # the defaults stay as they were)
        run_record.update({k: v for k, v in run_record.pop("settings").items()
                           if v is not None})
        record = {"dump_dir": str(dump_dir), "run": run_record,
                  "settings": settings.model_dump(mode="json"),
                  "steady_from_step": steady_from_step,
                  "checked_against_scene": False,
                  "flow": NO_FLOW, "controls": NO_CONTROLS,
                  "cases": [{"case_id": facts.case_id, "cg": facts.cg, "frames": len(frames),
                             "analysed": index.get(facts.case_id, 0)}],
                  "skipped_cases": [], "skipped_frames": skipped}
        AnalysisRecord.commit(outputs, record, obsolete=GRANULE_OUTPUTS)
        return record
    except BaseException:
        outputs.discard()
        raise
