"""README.md is a guide that stays true: short, its tables readable, every link resolving,
its example workflow valid with the cost it states, every ligwf command it shows accepted by
the parser, its two make targets what it says, and the demo's numbers it quotes those of
the committed demo report (docs/results/demo)."""

from __future__ import annotations

import re
import shlex

import pandas as pd
import pytest

from helpers import ROOT
from ligwf.cli.main import build_parser
from ligwf.pipeline.prepare import prepare_workflow
from ligwf.local import run_settings
from ligwf.pipeline.run import planned_schedule

README = ROOT / "README.md"
GUIDES = sorted((ROOT / "docs" / "guide").glob("*.md"))
LINKED = [README, *GUIDES, ROOT / "docs" / "cli.md", ROOT / "docs" / "architecture.md"]
DEMO = ROOT / "docs" / "results" / "demo"


def _text() -> str:
    return README.read_text()


def test_the_readme_is_short_and_its_tables_readable():
    assert len(_text().splitlines()) <= 200
    for page in [README, *GUIDES]:
        for n, line in enumerate(page.read_text().splitlines(), 1):
            if line.startswith("|"):
                cells = re.split(r"(?<!\\)\|", line)[1:-1]
                assert max(map(len, cells)) <= 200, f"{page.name}:{n}: a table cell over 200 chars"


@pytest.mark.parametrize("page", LINKED, ids=lambda p: p.name)
def test_every_relative_link_resolves(page):
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
        if "://" in target:
            continue
        assert (page.parent / target).exists(), f"{page.name}: broken link {target}"


def test_the_example_workflow_is_valid_and_costs_what_the_readme_says(tmp_path):
    block = re.search(r"```yaml\n(name: my-drum\n.*?)```", _text(), re.S).group(1)
    (tmp_path / "my_drum.yaml").write_text(block)
    prepared = prepare_workflow(tmp_path / "my_drum.yaml", [], [], False)
    assert len(prepared.rendered) == 10 and "10 cases" in _text()
    assert prepared.warnings == []
    minutes = planned_schedule(prepared, run_settings(cores=2)).estimated_seconds / 60
    assert "about 10 minutes on 2 cores" in _text() and 7 <= minutes <= 13


def test_every_command_the_readme_shows_is_accepted_by_the_parser(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    commands = {c for c in re.findall(r"`(ligwf [^`]+)`", _text())}
    assert len(commands) >= 6
    parser = build_parser()
    for command in commands:
        argv = shlex.split(command)[1:]
        try:
            parser.parse_args(argv)
        except SystemExit:
            pytest.fail(f"the README shows a command the parser refuses: {command}")
    study = build_parser()._subparsers._group_actions[0].choices["study"]
    for option in ("--max-looks", "--max-core-hours", "--until-decided"):
        assert option in _text() and option in study._option_string_actions


def test_the_make_targets_are_what_the_readme_says():
    makefile = (ROOT / "Makefile").read_text()
    demo = re.search(r"^demo: .*\n\t(.*)$", makefile, re.M).group(1)
    out = re.search(r"^DEMO_OUT \?= (\S+)$", makefile, re.M).group(1)
    shown = demo.replace("$(LIGWF)", "ligwf").replace("$(DEMO_OUT)", out)
    assert f"`make demo` is `{shown}`" in _text()
    assert re.search(r"^test: install", makefile, re.M) and "make test " in _text()


def test_the_demo_numbers_are_the_committed_report():
    timing = pd.read_csv(DEMO / "timing.csv").iloc[0]
    text = " ".join(_text().split())
    assert f"took {timing['wall_seconds']:.0f} s of wall on 2 cores" in text
    workflows = (ROOT / "docs" / "guide" / "workflows.md").read_text()
    assert f"`make demo`, {timing['wall_seconds'] / 60:.1f} min on 2 cores" in workflows
    summary = (DEMO / "summary.md").read_text()
    quoted = [line[2:].removeprefix("- ") for line in _text().splitlines()
              if line.startswith("> ") and line[2:].strip()]
    assert len(quoted) == 3
    for line in quoted:       # a quote may end in "..." (the rest of the report's line elided)
        assert line.removesuffix(" ...") in summary, \
            f"README quotes what the demo report does not say: {line}"
    # the README's reading of it: We-CG2's speedup, angle error and its bound, rounded
    verdict = pd.read_csv(DEMO / "verdict.csv")
    angle = verdict[(verdict["condition"] == "cg2-weber") & (verdict["criterion"] == "angle_deg")]
    row = angle.iloc[0]
    assert (f"We-CG2 is about {row['speedup_core']:.0f}x cheaper, but its angle of repose is "
            f"{row['value']:.1f} deg steeper than CG1's (shown within {row['shown_within']:.1f} "
            "deg)") in text and row["state"] == "fail"
    profile = verdict[(verdict["condition"] == "cg2-weber")
                      & (verdict["criterion"] == "profile_error")].iloc[0]
    assert "its velocity profile fails too" in text and profile["state"] == "fail"
