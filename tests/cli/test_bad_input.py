"""The bad-input corpus: every malformed workflow, override and option a hostile user tried.

Each input must end in exit code 2 with a ``ligwf: <Error>:`` message that names the field
(or option) and the offending value, no Python traceback, within 5 s, and nothing written
(the study folder is never created). The corpus is generated from the tiny drum workflow:
hand-written cases for every item reported, plus every numeric scene field with values
no number field accepts.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml

from ligwf.cli.main import main

from helpers import DRUM

BASE = DRUM.read_text()


@dataclass(frozen=True)
class Bad:
    """One bad input: the workflow text (None: the tiny drum), extra CLI words, and the
    fragments the error message must contain."""

    name: str
    expect: tuple[str, ...]
    text: str | bytes | None = None
    overrides: tuple[str, ...] = ()
    command: str = "render"
    options: tuple[str, ...] = ()
    setup: str = ""     # "out-file", "out-under-file", "cache-file", "study-listed-twice",
    #                     "out-empty", "out-workflow-folder", "workflow-symlink-loop",
    #                     "template-not-utf8", "out-symlink-loop"; extra["out"]: --out
    warns: bool = False                   # a documented warning (check exits 0), not a refusal
    seconds: float = 5.0                  # time allowed before the refusal
    extra: dict = field(default_factory=dict)


def _numeric_leaves(node, prefix=""):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _numeric_leaves(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield prefix


NUMERIC_FIELDS = [p for p in _numeric_leaves(yaml.safe_load(BASE)["scene"], "scene")
                  if ".size_distribution" not in p]
NOT_A_NUMBER = {".nan": "nan", "abc": "abc", "true": "True", "[1, 2]": "[1, 2]"}

LAUGHS = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + k)}: &{chr(98 + k)} [*{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, "
    f"*{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, "
    f"*{chr(97 + k)}, *{chr(97 + k)}]\n" for k in range(9)) + "scene: *j\n"

#: the facts ``analyse-dumps`` needs (its dump folder is the harness's workflow argument)
FOREIGN = ("--liquid", "washino", "--surface-tension", "0.2", "--contact-angle", "30",
           "--angle-convention", "engine", "--periodic-axis", "none", "--dt", "1e-5")
#: numeric scene fields whose physical floor is 0 or a value that stays finite when tiny
#: (a friction, a Poisson ratio, an angle or a settling time of 1e-300 is 0 in effect)
TINY_ACCEPTED = {"poisson_ratio", "friction", "contact_angle_deg", "settle_time"}

CORPUS: list[Bad] = [
    # --- the file itself (item 7) ---
    Bad("binary-bytes", ("workflow", "UTF-8"), text=b"name: x\nscene: \xff\xfe\x00\x01\n"),
    Bad("billion-laughs", ("alias",), text=LAUGHS),
    Bad("deep-nesting", ("nest",), text="scene: " + "[" * 10000 + "]" * 10000 + "\n",
        seconds=15.0),   # ~1 s alone; a hang (quadratic parse, recursion) takes minutes: 5 s failed under load
    Bad("top-key-int", ("1",), text="1: x\n" + BASE),
    Bad("top-key-null", ("None",), text="~: x\n" + BASE),
    Bad("scene-empty", ("scene",), text="name: x\nscene:\nsweep: {cg_levels: [1]}\n"),
    Bad("scene-list", ("scene", "[1, 2]"), overrides=("scene=[1, 2]",)),
    Bad("scene-string", ("scene", "drum"), overrides=("scene=drum",)),
    Bad("scene-null", ("scene", "None"), overrides=("scene=null",)),
    Bad("sweep-list", ("sweep", "[1, 2]"), text=BASE.split("sweep:")[0] + "sweep: [1, 2]\n"),
    Bad("sweep-set-list", ("sweep", "[1]"), overrides=("sweep=[1]",)),
    Bad("empty-file", ("scene",), text=""),
    Bad("only-comment", ("scene",), text="# nothing\n"),
    Bad("top-level-list", ("mapping",), text="- 1\n- 2\n"),
    Bad("top-level-scalar", ("mapping",), text="hello\n"),
    Bad("python-tag", ("tag",), text="x: !!python/object/apply:os.system [echo]\n" + BASE),
    Bad("unclosed-quote", ("workflow",), text=BASE + "description: 'open\n"),
    Bad("tab-indent", ("workflow",), text=BASE.replace("  drum:", "\tdrum:", 1)),
    Bad("duplicate-key", ("duplicate", "density"),
        text=BASE.replace("    density:", "    density: 1000\n    density:", 1)),
    Bad("unknown-top-key", ("sweeps",), text=BASE + "sweeps: {}\n"),
    Bad("unknown-scene-key", ("scene.drum.diameterr",), overrides=("scene.drum.diameterr=0.1",)),
    # --- overrides (items 8 and 9) ---
    Bad("set-no-equals", ("--set", "scene.drum.diameter"), overrides=("scene.drum.diameter",)),
    Bad("set-empty-key", ("--set", "empty key"), overrides=("=3",)),
    Bad("set-through-scalar", ("scene.drum.diameter",), overrides=("scene.drum.diameter.x=1",)),
    Bad("set-unknown-top", ("scen",), overrides=("scen.drum.diameter=1",)),
    Bad("set-bad-yaml", ("--set", "scene.drum.diameter"), overrides=("scene.drum.diameter=[1",)),
    Bad("replicas-huge", ("replicas", "300000"), overrides=("sweep.replicas=300000",)),
    Bad("replicas-zero", ("replicas", "0"), overrides=("sweep.replicas=0",)),
    Bad("replicas-negative", ("replicas", "-1"), overrides=("sweep.replicas=-1",)),
    Bad("cg-levels-zero", ("cg_levels", "0"), overrides=("sweep.cg_levels=[0]",)),
    Bad("cg-levels-negative", ("cg_levels", "-2"), overrides=("sweep.cg_levels=[-2]",)),
    Bad("cg-levels-empty", ("cg_levels",), overrides=("sweep.cg_levels=[]",)),
    Bad("rule-unknown", ("bnd",), overrides=("sweep.rules=[weber,bnd]",)),
    Bad("density-bool", ("density", "True"), overrides=("scene.particles.density=true",)),
    Bad("dump-every-step", ("dump_interval", "1e-12"),
        overrides=("scene.numerics.dump_interval=1e-12",)),
    Bad("per-cg-not-swept", ("per_cg", "5"), overrides=("sweep.per_cg={5: {process.run_time: 1}}",)),
    Bad("per-cg-bad-field", ("per_cg", "process.runtime"),
        overrides=("sweep.per_cg={2: {process.runtime: 1}}",)),
    Bad("count-overfills-drum", ("particle_count", "10000000"),
        overrides=("scene.process.particle_count=10000000",)),
    Bad("seed-above-int-max", ("seed", "2147483647"), overrides=("scene.numerics.seed=2147483647",)),
    Bad("name-nul", ("name",), overrides=("name=\"a\\0b\"",)),
    Bad("name-newline", ("name",), overrides=("name=\"a\\nb\"",)),
    Bad("name-dollar", ("name", "$"), overrides=("name=a$b",)),
    Bad("name-ampersand", ("name", "&"), overrides=("name=a&b",)),
    Bad("name-hash", ("name", "#"), overrides=("name=a#b",)),
    Bad("name-quote", ("name",), overrides=("name=a'b",)),
    Bad("name-c1-control", ("name", "\\x9b"), overrides=("name=\"a\\x9bb\"",)),
    # raw control characters on the command line: YAML folded NEL / U+2028 into a space
    # ("a b", accepted without a word) and an ESC was a ReaderError traceback (issue 32)
    Bad("set-raw-nel", ("--set name", "U+0085", "line 1, column 2"), overrides=("name=a\x85b",)),
    Bad("set-raw-line-separator", ("--set name", "U+2028"), overrides=("name=a\u2028b",)),
    Bad("set-raw-escape", ("--set name", "#x001b"), overrides=("name=a\x1bb",)),
    Bad("file-raw-nel", ("workflow", "U+0085", "line 2"),
        text=BASE.replace("name: drum-slice", "name: a\x85b")),
    Bad("wet-granules-hold-no-particle", ("scene.liquid.wet_granules.radius = 1e-07",
                                          "largest particle diameter", "allowed range"),
        overrides=("scene.liquid.placement=granules",
                   "scene.liquid.wet_granules={count: 2, radius: 1e-7}")),
    Bad("wet-granules-on-a-dry-bed", ("placement granules", "liquid.model 'none'", "dropped"),
        overrides=("scene.liquid.model=none", "scene.liquid.placement=granules",
                   "scene.liquid.wet_granules={count: 2, radius: 0.005}")),
    Bad("replicas-for-a-level-not-swept", ("sweep.replicas.3 = 5", "not swept", "not used"),
        overrides=("sweep.cg_levels=[1, 2]", "sweep.replicas={3: 5}"), command="check",
        warns=True, seconds=60.0),      # legal, surely unintended: a warning
    Bad("accept-all-null", ("accept: every tolerance is null",), command="check", warns=True,
        seconds=60.0,           # a warning: check renders and plans every case first
        overrides=("accept={angle_deg: null, profile_error: null, rigid_share: null, "
                   "flowing_layer: null, gsd_error: null, field_error: null}",)),
    Bad("rule-sweep-dry", ("rules", "dry"),
        overrides=("scene.liquid.model=none", "scene.analysis.contact_dumps=false",
                   "sweep.rules=[weber,bond]")),
    Bad("closed-drum-huge-particles", ("diameter",),
        overrides=("scene.drum.periodic=false", "scene.drum.length=0.02",
                   "scene.particles.size_distribution=[{diameter: 0.009, fraction: 1.0}]")),
    Bad("bridge-cut-below-rupture", ("warning", "max_separation_ratio = 1.01", "rupture"),
        overrides=("scene.liquid.max_separation_ratio=1.01",
                   "scene.liquid.min_separation_ratio=1.001"), command="check", warns=True),
    Bad("liquid-model-unknown", ("scene.liquid.model", "honey"),
        overrides=("scene.liquid.model=honey",)),
    Bad("fill-too-high", ("scene.process.fill_fraction", "0.9"),
        overrides=("scene.process.fill_fraction=0.9",)),
    Bad("lifter-too-high", ("lifters.height", "0.03"), overrides=("scene.drum.lifters.height=0.03",)),
    Bad("fractions-sum", ("size_distribution", "sum"),
        overrides=("scene.particles.size_distribution=[{diameter: 0.001, fraction: 0.5}]",)),
    Bad("axis-unknown", ("scene.drum.axis", "w"), overrides=("scene.drum.axis=w",)),
    # --- options (item 7) ---
    Bad("np-zero", ("--np", "0"), command="run", options=("--np", "0")),
    Bad("np-negative", ("--np", "-1"), command="run", options=("--np", "-1")),
    Bad("ensemble-negative", ("--ensemble", "-2"), command="run", options=("--ensemble", "-2")),
    Bad("out-is-file", ("--out",), setup="out-file"),
    Bad("out-under-file", ("--out",), setup="out-under-file"),
    Bad("mesh-cache-file", ("--mesh-cache",), setup="cache-file"),
    Bad("workflow-missing", ("no-such.yaml",), text=None, extra={"workflow": "no-such.yaml"}),
    Bad("workflow-name-markup", ("wf[test].yaml",), extra={"workflow": "wf[test].yaml"}),
    Bad("workflow-directory", ("directory",), text=None, extra={"workflow": "."}),
    Bad("templates-missing", ("--templates", "nowhere"), options=("--templates", "nowhere")),
    # --- issue 21: tracebacks, hangs and silent accepts ---
    Bad("community-seed-huge", ("analysis.community_seed", "99999999999999999999",
                                "[0, 4294967295]"),
        overrides=("analysis.community_seed=99999999999999999999",)),
    Bad("bootstrap-seed-huge", ("analysis.seed", "[0, 4294967295]"),
        overrides=("analysis.seed=18446744073709551616",)),
    Bad("steady-after-text", ("analysis.steady_after", "without quotes"),
        overrides=("analysis.steady_after='0.25'",)),
    Bad("description-explicit-date", ("description", "date", "quote it"),
        text=BASE.replace("description: ", "description: !!timestamp 2024-01-01 #", 1)),
    Bad("binary-value", ("name", "bytes"), overrides=("name=!!binary aGVsbG8=",)),
    Bad("rpm-base-60", ("scene.process.rotation.rpm = '1:30'", "base-60", "90"),
        overrides=("scene.process.rotation.rpm=1:30",)),
    Bad("density-yes", ("scene.particles.density = 'yes'", "yes/no word"),
        overrides=("scene.particles.density=yes",)),
    Bad("friction-off", ("scene.particles.friction = 'off'", "yes/no word"),
        overrides=("scene.particles.friction=off",)),
    Bad("count-octal", ("scene.drum.lifters.count = '012'", "octal"),
        overrides=("scene.drum.lifters.count=012",)),
    Bad("count-hex", ("scene.drum.lifters.count = '0x0c'", "decimal"),
        overrides=("scene.drum.lifters.count=0x0c",)),
    Bad("density-quoted", ("scene.particles.density = '2500'", "without quotes", "[10, 100000]"),
        overrides=('scene.particles.density="2500"',)),
    Bad("diameter-range-quoted", ("scene.particles.size_distribution[0].diameter_range[1]",
                                  "'0.002'"),
        overrides=("scene.particles.size_distribution=[{diameter_range: [0.001, '0.002'], "
                   "fraction: 1.0}]",)),
    Bad("cg-levels-true", ("sweep.cg_levels[0] = True", "yes/no"),
        overrides=("sweep.cg_levels=[true]",)),
    Bad("replicas-text", ("sweep.replicas[2] = 'x'",), overrides=("sweep.replicas={1: 1, 2: x}",)),
    Bad("liquid-content-whole", ("scene.liquid.liquid_content = 1", "[1e-05, 0.2]", "pendular"),
        overrides=("scene.liquid.liquid_content=1",)),
    Bad("surface-tension-denormal", ("scene.liquid.surface_tension", "physical floor", "0 to"),
        overrides=("scene.liquid.surface_tension=1e-300",)),
    Bad("size-denormal", ("scene.particles.size_distribution[0].diameter = 5e-324", "[1e-06, 1]"),
        overrides=("scene.particles.size_distribution=[{diameter: 5e-324, fraction: 1.0}]",)),
    Bad("fraction-denormal", ("scene.particles.size_distribution[1].fraction = 1e-300",
                              "[1e-06, 1]"),
        overrides=("scene.particles.size_distribution=[{diameter: 0.001, fraction: 1.0}, "
                   "{diameter: 0.002, fraction: 1e-300}]",)),
    Bad("range-denormal", ("scene.particles.size_distribution[0].diameter_range", "1e-06 m"),
        overrides=("scene.particles.size_distribution=[{diameter_range: [1e-300, 1e-3], "
                   "fraction: 1.0}]",)),
    Bad("dt-denormal", ("scene.numerics.dt = 5e-324", "[1e-10, 1]"),
        overrides=("scene.numerics.dt=5e-324",)),
    Bad("froude-denormal", ("scene.process.rotation.froude", "[1e-06, 100]"),
        overrides=("scene.process.rotation={froude: 1e-300}",)),
    Bad("lifter-height-denormal", ("scene.drum.lifters.height = 1e-300", "[1e-06, 0.025) m"),
        overrides=("scene.drum.lifters.height=1e-300",)),
    Bad("thermo-longer-than-run", ("scene.numerics.thermo_interval = 0.6", "run_time",
                                   "allowed range [1e-06, 0.101] s"),
        overrides=("scene.numerics.thermo_interval=0.6",)),
    Bad("thermo-stretches-fill", ("scene.numerics.thermo_interval = 0.3", "fall across the drum"),
        overrides=("scene.numerics.thermo_interval=0.3",)),
    Bad("thermo-longer-than-short-run", ("scene.numerics.thermo_interval = 0.05",
                                         "process.run_time = 0.04", "[1e-06, 0.04] s"),
        overrides=("scene.process.run_time=0.04", "scene.numerics.thermo_interval=0.05",
                   "scene.numerics.dump_interval=0.01")),
    Bad("dump-longer-than-run", ("scene.numerics.dump_interval = 0.6", "no frame",
                                 "[1e-06, 0.5] s"),
        overrides=("scene.numerics.dump_interval=0.6",)),
    Bad("per-cg-dump-longer-than-run", ("sweep.per_cg.2 -> scene.numerics.dump_interval",
                                        "no frame"),
        overrides=("sweep.per_cg={2: {process.run_time: 0.04}}",)),
    Bad("no-cg1-to-compare", ("warning", "sweep.cg_levels = [2, 3]", "no CG1 case"),
        overrides=("sweep.cg_levels=[2, 3]",), command="check", warns=True),
    Bad("one-cg1-replica", ("warning", "sweep.replicas = 1 at CG1", "indicative", "undecided"),
        overrides=("sweep.cg_levels=[1, 2]", "sweep.replicas=1"), command="check", warns=True),
    Bad("case-folders-collide", ("sweep.scene.name", "'a b' and 'a-b'", "same case folder"),
        overrides=("sweep.scene.name=['a b', 'a-b']",)),
    Bad("case-folders-collide-signed-zero", ("sweep.scene.particles.rolling_friction",
                                             "0.0 and -0.0", "same case folder"),
        overrides=("sweep.scene.particles.rolling_friction=[0.0, -0.0]",)),
    Bad("case-folders-collide-slurm-dry-run", ("0.0 and -0.0", "same case folder"),
        overrides=("sweep.scene.particles.rolling_friction=[0.0, -0.0]",),
        command="slurm submit", options=("--dry-run",)),
    Bad("rule-unknown-path", ("sweep.rules[1] = 'bnd'",), overrides=("sweep.rules=[weber,bnd]",)),
    Bad("fractions-sum-path", ("scene.particles.size_distribution: the fractions sum to 0.5",),
        overrides=("scene.particles.size_distribution=[{diameter: 0.001, fraction: 0.5}]",)),
    Bad("run-longer-than-one-run-command", ("process.run_time = 0.5 s", "2,147,483,647",
                                            "numerics.dt"),
        overrides=("scene.numerics.dt=1e-10", "scene.process.settle_time=0.1")),
    Bad("lifters-overlap-path", ("scene.drum.lifters.count = 100", "[0, 89] lifters"),
        overrides=("scene.drum.lifters={count: 100, height: 0.002, width_deg: 4}",)),
    Bad("output-count-path", ("scene.numerics.dump_interval = 1e-09",),
        overrides=("scene.numerics.dump_interval=1e-9",)),
    Bad("mpirun-args-unclosed-quote", ("LIGWF_MPIRUN_ARGS", '\'"--bind-to\'', "no closing"),
        command="run", overrides=("sweep.cg_levels=[3]", "sweep.rules=[bond]"),
        extra={"env": {"LIGWF_MPIRUN_ARGS": '"--bind-to'}}),
    Bad("site-mpirun-args-unclosed-quote", ("site file", "mpirun_args", "no closing"),
        command="run", overrides=("sweep.cg_levels=[3]", "sweep.rules=[bond]"),
        extra={"site": "mpirun_args: \"'--bind-to\"\n"}),
    Bad("sbatch-args-unclosed-quote", ("slurm sbatch_args", "no closing"),
        command="slurm submit", options=("--dry-run",),
        extra={"env": {"LIGWF_SLURM_SBATCH_ARGS": '"--foo'}}),
    Bad("site-mpirun-args-mapping", ("site file", "mpirun_args is a dict", "list of arguments"),
        command="run", overrides=("sweep.cg_levels=[3]", "sweep.rules=[bond]"),
        extra={"site": "mpirun_args: {a: 1}\n"}),
    *(Bad(f"slurm-time-{name}", ("slurm time", repr(value), why), command="slurm submit",
          options=("--dry-run", "--time", value))
      for name, value, why in (("seconds-99", "1:99:99", "allowed range [0, 59]"),
                               ("mm-ss-99", "1:99", "allowed range [0, 59]"),
                               ("day-hours-99", "1-99", "allowed range [0, 23]"),
                               ("20-digits", "9" * 20, "longer than 365 days"))),
    Bad("workflow-symlink-loop", ("workflow file", "loop.yaml", "symbolic links"),
        command="check", setup="workflow-symlink-loop"),
    Bad("template-not-utf8", ("template drum.in.j2", "not UTF-8", "0xff"),
        setup="template-not-utf8"),
    Bad("render-out-empty", ("--out", "empty path", "current folder"), setup="out-empty"),
    Bad("run-out-empty", ("--out", "empty path"), command="run", setup="out-empty"),
    Bad("render-out-workflow-folder", ("--out", "folder of the workflow file"),
        setup="out-workflow-folder"),
    Bad("engine-missing", ("LIGGGHTS executable '/nonexistent/liggghts' not found",),
        command="run", extra={"env": {"LIGWF_LIGGGHTS": "/nonexistent/liggghts"}}),
    Bad("engine-missing-np", ("LIGGGHTS executable '/nonexistent/liggghts' not found",),
        command="run", options=("--np", "1"),
        extra={"env": {"LIGWF_LIGGGHTS": "/nonexistent/liggghts"}}),
    Bad("engine-without-library", ("/bin/true", "does not link to a libliggghts"),
        command="run", extra={"env": {"LIGWF_LIGGGHTS": "/bin/true"}}),
    Bad("mpirun-missing", ("MPI launcher '/nonexistent/mpirun' not found",),
        command="run", extra={"env": {"LIGWF_MPIRUN": "/nonexistent/mpirun"}}),
    Bad("library-setting-retired", ("LIGWF_LIBLIGGGHTS", "no longer read", "LIGWF_LIGGGHTS"),
        command="run", extra={"env": {"LIGWF_LIBLIGGGHTS": "/x/libliggghts.so"}}),
    Bad("site-library-key-retired", ("site file", "libliggghts", "no longer read"),
        command="run", extra={"site": "libliggghts: /x/libliggghts.so\n"}),
    Bad("site-unknown-key", ("site file", "mpirun_arg", "typo"),
        command="run", overrides=("sweep.cg_levels=[3]", "sweep.rules=[bond]"),
        extra={"site": "mpirun_arg: --bind-to none\n"}),
    Bad("report-case-listed-twice", ("study.json", "cg3-bond-r0", "more than"),
        command="report", setup="study-listed-twice",
        seconds=30.0),   # report imports scipy.stats and matplotlib before it reads the study
    Bad("np-huge", ("--np", "[1, 1048576]", "1000000000000"), command="run",
        options=("--np", "1000000000000")),
    Bad("ensemble-huge", ("--ensemble", "[1, 1048576]"), command="study",
        options=("--ensemble", "1048577")),
    Bad("cores-huge", ("--cores", "[1, 1048576]"), command="check",
        options=("--cores", "99999999999999")),
    Bad("ntasks-huge", ("--ntasks", "[1, 1048576]"), command="slurm submit",
        options=("--dry-run", "--ntasks", "1000000000000")),
    Bad("analyse-dumps-set-bad-yaml", ("--set seed", "not valid YAML"),
        command="analyse-dumps", overrides=("seed=[1",), options=FOREIGN),
    Bad("analyse-dumps-dt-denormal", ("--dt", "[1e-10, 1] s", "5e-324"),
        command="analyse-dumps", options=(*FOREIGN[:-1], "5e-324")),
    Bad("analyse-dumps-surface-tension-inf", ("--surface-tension", "[1e-06, 10000] N/m", "inf"),
        command="analyse-dumps", options=(*FOREIGN[:2], "--surface-tension", "inf",
                                          *FOREIGN[4:])),
    Bad("analyse-dumps-surface-tension-1e300", ("--surface-tension", "[1e-06, 10000] N/m"),
        command="analyse-dumps", options=(*FOREIGN[:2], "--surface-tension", "1e300",
                                          *FOREIGN[4:])),
    Bad("analyse-dumps-contact-angle-200", ("--contact-angle", "[0, 180] deg"),
        command="analyse-dumps", options=(*FOREIGN[:4], "--contact-angle", "200",
                                          *FOREIGN[6:])),
    Bad("analyse-dumps-steady-step-huge", ("--steady-from-step", "[0, 2,147,483,647]"),
        command="analyse-dumps", options=(*FOREIGN, "--steady-from-step", str(10**12))),
    Bad("report-out-a-file", ("--out", "is a file, not a folder"), command="report",
        setup="out-file"),
    Bad("analyse-dumps-cg-zero", ("--cg", "[1, 1000]", "'0'"),
        command="analyse-dumps", options=(*FOREIGN, "--cg", "0")),
    Bad("analyse-dumps-liquid-content-whole", ("--liquid-content", "[1e-05, 0.2]"),
        command="analyse-dumps", options=(*FOREIGN, "--liquid-content", "1")),
    Bad("analyse-dumps-seed-huge", ("analysis.community_seed", "[0, 4294967295]"),
        command="analyse-dumps", overrides=("community_seed=99999999999999999999",),
        options=FOREIGN),
    # --- issue 46: nothing injected, no traceback ---
    Bad("alias-cycle-description", ("alias refers to the value that holds it", "line 3"),
        text=BASE.replace("description: Small", "description: &d [*d]\nx_was: Small", 1)),
    Bad("alias-cycle-scene", ("alias refers to the value that holds it",),
        text=BASE.replace("scene:\n", "scene: &s\n  self: *s\n", 1)),
    Bad("alias-cycle-sweep", ("alias refers to the value that holds it",),
        text=BASE.split("sweep:")[0] + "sweep: &w {cg_levels: [1], again: *w}\n"),
    Bad("alias-cycle-accept", ("alias refers to the value that holds it",),
        text=BASE + "accept: &a [*a]\n"),
    Bad("alias-bomb-scene", ("alias",), text=LAUGHS.replace("scene: *j", "scene: {x: *j}")),
    Bad("alias-bomb-sweep", ("alias",), text=LAUGHS.replace("scene: *j", "sweep: *j")),
    Bad("alias-bomb-accept", ("alias",), text=LAUGHS.replace("scene: *j", "accept: {a: *j}")),
    Bad("out-newline-render", ("--out", "line break", "one line"),
        extra={"out": "s\ntouch PWNED\n#"}),
    Bad("out-newline-run", ("--out", "line break"), command="run",
        extra={"out": "s\ntouch PWNED\n#"}),
    Bad("out-newline-slurm", ("--out", "line break"), command="slurm submit",
        options=("--dry-run",), extra={"out": "runs/s\ntouch PWNED\n#"}),
    Bad("out-carriage-return", ("--out", "carriage return"), extra={"out": "s\rx"}),
    Bad("out-escape", ("--out", "U+001B"), command="study", extra={"out": "s\x1b[2Jx"}),
    Bad("out-symlink-loop", ("--out", "symbolic link loop"), setup="out-symlink-loop"),
    Bad("out-over-4096", ("--out", "allowed at most 4,095", "PATH_MAX"),
        extra={"out": "a/" * 2100}),
    Bad("out-name-over-255", ("--out", "NAME_MAX"), command="run", extra={"out": "n" * 300}),
    Bad("set-newline", ("--set", "line break", "one line"),
        overrides=("scene.name=a\nshell x",)),
    Bad("set-carriage-return", ("--set", "carriage return"), overrides=("name=a\rb",)),
]
CORPUS += [Bad(f"{path}={raw}", (path.rpartition(".")[2], shown), overrides=(f"{path}={raw}",))
           for path in NUMERIC_FIELDS for raw, shown in NOT_A_NUMBER.items()]
# below every physical floor (issue 21: ZeroDivisionError / OverflowError in the scaling)
CORPUS += [Bad(f"{path}={raw}", (path, "allowed"), overrides=(f"{path}={raw}",))
           for path in NUMERIC_FIELDS if path.rpartition(".")[2] not in TINY_ACCEPTED
           for raw in ("1e-300", "5e-324")]


def test_the_corpus_is_large_enough():
    assert len(CORPUS) >= 120, len(CORPUS)
    assert len({b.name for b in CORPUS}) == len(CORPUS)


@pytest.mark.timeout(30)
@pytest.mark.parametrize("bad", CORPUS, ids=lambda b: b.name)
def test_bad_input_ends_in_one_clear_error(bad: Bad, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "cache"))
    workflow = Path(bad.extra.get("workflow", tmp_path / "wf.yaml"))
    if "workflow" not in bad.extra:
        content = BASE if bad.text is None else bad.text
        (workflow.write_bytes if isinstance(content, bytes) else workflow.write_text)(content)
    out = tmp_path / "study"
    if bad.setup == "out-file":
        out.write_text("a file")
    elif bad.setup == "out-under-file":
        (tmp_path / "afile").write_text("a file")
        out = tmp_path / "afile" / "sub"
    elif bad.setup == "out-workflow-folder":
        out = workflow.parent
    elif bad.setup == "workflow-symlink-loop":
        workflow = tmp_path / "loop.yaml"
        workflow.symlink_to(workflow)
    elif bad.setup == "out-symlink-loop":             # loop/a -> b, loop/b -> a
        (tmp_path / "loop").mkdir()
        (tmp_path / "loop" / "a").symlink_to("b")
        (tmp_path / "loop" / "b").symlink_to("a")
        out = tmp_path / "loop" / "a" / "x"
    if "out" in bad.extra:
        out = tmp_path / bad.extra["out"]
    options = list(bad.options)
    if bad.setup == "cache-file":
        (tmp_path / "cachefile").write_text("x")
        options += ["--mesh-cache", str(tmp_path / "cachefile")]
    if bad.setup == "template-not-utf8":
        (tmp_path / "templates").mkdir()
        (tmp_path / "templates" / "drum.in.j2").write_bytes(b"\xff\xfe latin-1 \xe9")
        options += ["--templates", str(tmp_path / "templates")]
    for name, value in bad.extra.get("env", {}).items():
        monkeypatch.setenv(name, value)
    if "site" in bad.extra:
        (tmp_path / "site.yaml").write_text(bad.extra["site"])
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "site.yaml"))
    if bad.setup == "study-listed-twice":     # a rendered study whose record repeats a case
        study = tmp_path / "rendered"
        assert main(["render", str(workflow), "--out", str(study), "--set", "sweep.cg_levels=[3]",
                     "--set", "sweep.rules=[bond]"]) == 0
        record = json.loads((study / "study.json").read_text())
        record["cases"].append(record["cases"][0])
        (study / "study.json").write_text(json.dumps(record))
        capsys.readouterr()
        workflow = study
    before = sorted(p.name for p in tmp_path.iterdir())
    argv = [*bad.command.split(), str(workflow), *options]
    if bad.command != "check":
        argv += ["--out", "" if bad.setup == "out-empty" else str(out)]
    for o in bad.overrides:
        argv += ["--set", o]
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == (0 if bad.warns else 2), f"exit {code}, stderr:\n{err}"
    assert "Traceback" not in err
    assert err.startswith("ligwf: "), err
    flat = " ".join(err.split())     # the console wraps long lines
    for frag in bad.expect:
        assert frag in flat, f"{frag!r} not in the message:\n{err}"
    assert "= {'" not in flat, f"a whole mapping instead of its field:\n{err}"
    assert elapsed < bad.seconds, f"{elapsed:.1f} s before the refusal"
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "something was written"


def test_the_planner_refuses_more_ranks_than_it_can_lay_out():
    """The CLI refuses --np / --ensemble above MAX_RANKS; the planner does too, for callers
    that build run settings themselves (the processor-grid search is linear in the ranks)."""
    from ligwf.engine.plan import MAX_RANKS, CaseLoad, override_schedule
    from ligwf.errors import ConfigError

    loads = [CaseLoad("c", 1000, 100, 0.01, 0.001)]
    assert override_schedule(loads, MAX_RANKS).phases[0].ranks == MAX_RANKS
    for kwargs in ({"nprocs": 10**12}, {"nprocs": 1, "ensemble": MAX_RANKS + 1}):
        with pytest.raises(ConfigError, match=r"allowed range \[1, 1048576\] MPI ranks"):
            override_schedule(loads, **kwargs)
