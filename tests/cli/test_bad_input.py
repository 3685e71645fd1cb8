"""The bad-input corpus: every malformed workflow, override and option a hostile user tried.

Each input must end in exit code 2 with a ``ligwf: <Error>:`` message that names the field
(or option) and the offending value, no Python traceback, within 5 s, and nothing written
(the study folder is never created). The corpus is generated from the tiny drum workflow:
hand-written cases for every item reported, plus every numeric scene field with values
no number field accepts.
"""

from __future__ import annotations

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
    setup: str = ""                       # "out-file", "out-under-file", "cache-file"
    warns: bool = False                   # a documented warning (check exits 0), not a refusal
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

CORPUS: list[Bad] = [
    # --- the file itself (item 7) ---
    Bad("binary-bytes", ("workflow", "UTF-8"), text=b"name: x\nscene: \xff\xfe\x00\x01\n"),
    Bad("billion-laughs", ("alias",), text=LAUGHS),
    Bad("deep-nesting", ("nest",), text="scene: " + "[" * 10000 + "]" * 10000 + "\n"),
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
    Bad("rule-sweep-dry", ("rules", "dry"),
        overrides=("scene.liquid.model=none", "scene.analysis.granules=false",
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
    Bad("workflow-directory", ("directory",), text=None, extra={"workflow": "."}),
    Bad("templates-missing", ("--templates", "nowhere"), options=("--templates", "nowhere")),
]
CORPUS += [Bad(f"{path}={raw}", (path.rpartition(".")[2], shown), overrides=(f"{path}={raw}",))
           for path in NUMERIC_FIELDS for raw, shown in NOT_A_NUMBER.items()]


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
    options = list(bad.options)
    if bad.setup == "cache-file":
        (tmp_path / "cachefile").write_text("x")
        options += ["--mesh-cache", str(tmp_path / "cachefile")]
    before = sorted(p.name for p in tmp_path.iterdir())
    argv = [bad.command, str(workflow), *options]
    if bad.command != "check":
        argv += ["--out", str(out)]
    for o in bad.overrides:
        argv += ["--set", o]
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == (0 if bad.warns else 2), f"exit {code}, stderr:\n{err}"
    assert "Traceback" not in err
    assert err.startswith("ligwf: "), err
    for frag in bad.expect:
        assert frag in err, f"{frag!r} not in the message:\n{err}"
    assert elapsed < 5.0, f"{elapsed:.1f} s before the refusal"
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "something was written"
