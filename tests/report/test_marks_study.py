"""No report marks an error against what its interval says, and the verdict agrees with its
intervals: over the report tables of a tiny real study (real LIGGGHTS runs, two CG1
replicas so the floor is measured) and of the same study stopped by SIGTERM in a run and
resumed (the issue's case: a resumed run read "within" where the first read "beyond").

For every error column of conditions.csv: ``beyond`` only when lo > floor, ``within`` only
when hi <= floor, ``undecided`` only when neither holds (or there is no interval). For
every criterion of verdict.csv: signed ones (angle, rigid share) ``pass`` only inside
+-budget and ``fail`` only wholly outside, their value recomputed from cases.csv (the
difference of run means); norm ones ``pass`` only when hi <= budget, ``fail`` only when
lo > budget. summary.md and index.html open with the
verdict, and ``ligwf study`` ends by printing its sentence.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from ligwf.inference import equivalence as eq

from ligwf.study import layout
from ligwf.study.manifest import read_manifest

from apistudy import api_study, api_study_stdout
from helpers import ROOT

pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"
#: two CG1 replicas (a measured floor), two per CG2 rule; a production long enough to be hit
SETS = ["--no-snapshots", "--set", "sweep.replicas={1: 2, 2: 2}",
        "--set", "scene.process.run_time=0.4"]


def study_command(out: Path) -> list[str]:
    return [sys.executable, "-m", "ligwf.cli.main", "study", str(TINY), "--out", str(out),
            "--mesh-cache", str(out.parent / "meshes"), *SETS]


def run_study(out: Path) -> subprocess.CompletedProcess:
    r = subprocess.run(study_command(out), capture_output=True, text=True, timeout=3000)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "Traceback" not in r.stderr
    return r


def _text(path: Path) -> str:
    try:
        return path.read_text(errors="replace")
    except OSError:
        return ""


@pytest.fixture(scope="module")
def fresh(engine, tmp_path_factory):
    """The session's fresh tiny study under both rules (tests/apistudy.py: two CG1 and two
    CG2 replicas a rule, the CG1 runs' cohesionless twins) and what ``ligwf study`` printed."""
    return (api_study(engine, tmp_path_factory),
            api_study_stdout(engine, tmp_path_factory))


@pytest.fixture(scope="module")
def resumed(tmp_path_factory):
    """Stopped by SIGTERM while a case is in production, then ``ligwf study`` again."""
    out = tmp_path_factory.mktemp("marks") / "resumed"
    proc = subprocess.Popen(study_command(out), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    t0 = time.monotonic()
    try:
        while proc.poll() is None and time.monotonic() - t0 < 1500:
            logs = [_text(p) for p in out.glob(f"*/{layout.SCREEN_FILE}")]
            if any("ligwf-phase production" in t for t in logs):
                time.sleep(1.0)   # inside the production, not at its first step
                os.kill(proc.pid, signal.SIGTERM)
                break
            time.sleep(0.2)
        proc.wait(timeout=300)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    killed = [d.name for d in out.iterdir() if (d / layout.MANIFEST_FILE).is_file()
              and read_manifest(d).status == "killed"]
    assert killed, "the SIGTERM should have stopped a case in its run"
    return out, run_study(out), killed


def check_marks(report: Path) -> int:
    """Every ``_vs_floor`` mark of conditions.csv against its interval; returns how many
    marks were checked."""
    conds = pd.read_csv(report / layout.CONDITIONS_REPORT)
    checked = 0
    for mark_col in [c for c in conds if c.endswith("_vs_floor")]:
        col = mark_col.removesuffix("_vs_floor")
        for _, r in conds.iterrows():
            mark, lo, hi, floor = (r[mark_col], r[f"{col}_lo"], r[f"{col}_hi"],
                                   r[f"{col}_floor"])
            where = f"{col} of cg{r['cg']:g}-{r['rule']} {r['group']}: {mark} [{lo}, {hi}] vs {floor}"
            if mark == "beyond":
                assert lo > floor, where
            elif mark == "within":
                assert hi <= floor, where
            elif isinstance(mark, str) and mark.startswith("undecided"):
                assert not (math.isfinite(lo) and math.isfinite(hi)) or not (
                    lo > floor or hi <= floor), where
            else:
                assert mark in ("reference", "–") or pd.isna(mark), where
                continue
            checked += 1
    return checked


def check_verdict(report: Path) -> pd.DataFrame:
    """Every criterion of verdict.csv against its interval, and the signed ones recomputed
    from the per-run values of cases.csv (Welch on run means, two one-sided tests)."""
    verdict = pd.read_csv(report / layout.VERDICT_TABLE)
    conds = pd.read_csv(report / layout.CONDITIONS_REPORT)
    cases = pd.read_csv(report / layout.CASES_REPORT)
    assert len(verdict), "a study with CG1 and CG2 has a verdict"
    signed = {"angle_deg": "angle_of_repose", "rigid_share": "rigid_frame_share"}
    for _, v in verdict.iterrows():
        where = f"{v['condition']} {v['criterion']}: {v['state']} [{v['lo']}, {v['hi']}] vs {v['budget']}"
        if v["state"] not in ("pass", "fail", "undecided"):
            assert v["state"] in ("not assessed", "not measured"), where
            continue
        if v["criterion"] in signed:
            if v["state"] == "pass":
                assert -v["budget"] <= v["lo"] and v["hi"] <= v["budget"], where
            elif v["state"] == "fail":
                assert v["lo"] > v["budget"] or v["hi"] < -v["budget"], where
            col = signed[v["criterion"]]
            in_group = cases[cases["group"] == v["group"]]
            arm = in_group[(in_group["cg"] == v["cg"]) & (in_group["rule"] == v["rule"])]
            ref = in_group[in_group["cg"] == 1.0]
            e = eq.difference_estimate(arm[col], ref[col])
            assert v["value"] == pytest.approx(e.value), where
            assert v["budget"] == pytest.approx(1.0 if col == "angle_of_repose" else 0.05)
        elif v["state"] == "pass":
            assert v["hi"] <= v["budget"], where
        elif v["state"] == "fail":
            assert v["lo"] > v["budget"], where
        row = conds[(conds["group"] == v["group"]) & (conds["cg"] == v["cg"])
                    & (conds["rule"] == v["rule"])].iloc[0]
        assert v["speedup_core"] == pytest.approx(row["speedup_core"]), where
    # a condition meets the budget only when every assessed criterion passes
    for name, sub in verdict.groupby("condition"):
        assessed = sub[sub["state"].isin(["pass", "fail", "undecided"])]
        meets = sub["condition_state"].iloc[0] == "meets the budget"
        assert meets == (len(assessed) > 0 and (assessed["state"] == "pass").all()), name
        if (sub["cheapest"]).any():
            assert meets, name
    return verdict


def check_pages(report: Path, stdout: str) -> None:
    import json

    record = json.loads((report / layout.VERDICT_RECORD).read_text())
    sentences = [g["sentence"] for g in record["groups"]]
    assert sentences
    md = (report / layout.SUMMARY_REPORT).read_text()
    first_section = next(line for line in md.splitlines() if line.startswith("## "))
    assert first_section == "## Verdict", "summary.md opens with the verdict"
    page = (report / layout.HTML_REPORT).read_text()
    assert page.index('id="verdict"') < page.index("<h2>Cases</h2>")
    said = " ".join(stdout.split())
    for s in sentences:
        assert f"**{s}**" in md
        assert " ".join(s.split()) in said, "ligwf study ends with the verdict's sentence"


def test_fresh_study_marks_and_verdict_agree_with_their_intervals(fresh):
    out, stdout = fresh
    assert check_marks(out / "report") > 0
    verdict = check_verdict(out / "report")
    assert set(verdict["condition"]) == {"cg2-weber", "cg2-bond"}
    check_pages(out / "report", stdout)


def test_resumed_study_marks_and_verdict_agree_with_their_intervals(resumed):
    out, r, killed = resumed
    for cid in killed:   # the stopped case was resumed, not started over
        m = read_manifest(out / cid)
        assert m.status == "done" and [a.status for a in m.attempts][-2:] == ["killed", "done"]
    assert check_marks(out / "report") > 0
    check_verdict(out / "report")
    check_pages(out / "report", r.stdout)
