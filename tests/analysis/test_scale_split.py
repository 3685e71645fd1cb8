"""Analysis split over ranks or array tasks (#24): shares, partial outputs, checks once.

The end-to-end comparison (a study analysed by a real Slurm array gives the local
analysis' tables byte for byte) is tests/slurm/test_analysis_array.py; here the pieces
it rests on, without the engine.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

import ligwf.study.case as case_module
from ligwf.analysis.frames.checks import ExpectedFrames, shared_checks
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.parts import (AnalysisIncomplete, Share, check_count, check_token,
                                  parse_part, read_parts, write_part)
from ligwf.analysis.runner import AnalysisShares
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import file_sha256 as file_digest
from ligwf.study.case import DumpRecord


@pytest.mark.parametrize("text, index, count", [("0/1", 0, 1), ("3/8", 3, 8), (" 9 / 10 ", 9, 10)])
def test_parse_part(text, index, count):
    assert parse_part(text) == (index, count)


@pytest.mark.parametrize("text, words", [("8/8", "task index 8 outside the allowed range [0, 7]"),
                                         ("1/0", "allowed range [1, 10000]"),
                                         ("a/2", "expected K/N"),
                                         ("-1/2", "expected K/N")])
def test_parse_part_refuses_with_value_and_range(text, words):
    with pytest.raises(ConfigError, match=words.replace("[", r"\[").replace("]", r"\]")):
        parse_part(text)


def test_count_and_token_checks():
    assert check_count(4) == 4
    for bad in (0, 10_001, True, 2.5):
        with pytest.raises(ConfigError, match="allowed range"):
            check_count(bad)
    assert check_token("ab12") == "ab12"
    for bad in ("", "a/b", "x" * 33, "a b", "../up"):
        with pytest.raises(ConfigError, match="--token"):
            check_token(bad)


def _plan(frames_per_case: list[int], extra_cases: int = 0) -> AnalysisShares:
    facts = [SimpleNamespace(case_id=f"c{k}") for k in range(len(frames_per_case))]
    usable = [SimpleNamespace(case_id=f"c{k}") for k in range(len(frames_per_case) + extra_cases)]
    tasks = [(fi, FrameFiles(step, Path(f"p{step}"), None))
             for fi, n in enumerate(frames_per_case) for step in range(n)]
    return AnalysisShares(None, None, None, usable, [], [], [], facts, tasks)


@pytest.mark.parametrize("size", [1, 2, 3, 7, 40])
def test_shares_are_contiguous_and_cover_everything_once(size):
    plan = _plan([5, 1, 9, 0, 4], extra_cases=2)
    got, flows = [], []
    for rank in range(size):
        tasks, cases = plan.share(rank, size)
        got += tasks
        flows += [c.case_id for c in cases]
        # contiguous: one run of the task list
        if tasks:
            first = plan.tasks.index(tasks[0])
            assert plan.tasks[first:first + len(tasks)] == tasks
        # a case's flow goes with its middle frame
        for c in cases:
            ks = [k for k, (fi, _) in enumerate(plan.tasks) if plan.facts[fi].case_id == c.case_id]
            if ks:
                assert plan.tasks[ks[len(ks) // 2]] in tasks
    assert got == plan.tasks
    assert sorted(flows) == sorted(c.case_id for c in plan.usable)


def test_merge_names_missing_and_foreign_parts(tmp_path):
    for index in (0, 2):
        write_part(tmp_path, "tok1", index, 4, "fp", Share())
    write_part(tmp_path, "tok1", 3, 4, "other plan", Share())
    with pytest.raises(AnalysisIncomplete) as exc:
        read_parts(tmp_path, "tok1", 4, "fp", "ligwf analyse S --part {index}/4 --token tok1")
    msg = str(exc.value)
    assert "task(s) 1 of 4 left no partial output" in msg
    assert "3 (computed for another plan" in msg
    assert "ligwf analyse S --part 1/4 --token tok1" in msg and "\n" not in msg
    write_part(tmp_path, "tok1", 1, 4, "fp", Share())
    write_part(tmp_path, "tok1", 3, 4, "fp", Share(notes={"c0": ["n"]}))
    shares = read_parts(tmp_path, "tok1", 4, "fp", "")
    assert [s.notes for s in shares] == [{}, {}, {}, {"c0": ["n"]}]
    assert not list(tmp_path.glob(".parts-tok1/.*tmp"))         # atomic: no temporaries


def test_each_dump_is_hashed_once_per_analysis_and_again_when_changed(tmp_path, monkeypatch):
    dump = tmp_path / "particles_10.vtu"
    dump.write_bytes(b"<VTKFile>one</VTKFile>")
    plan = ExpectedFrames("c", (), (), 1, DumpRecord("h", 10, {dump.name: (dump.stat().st_size,
                                                                         file_digest(dump))}))
    calls = []

    def counting(path):
        calls.append(path)
        return file_digest(path)

    monkeypatch.setattr(case_module, "file_sha256", counting)
    ff = FrameFiles(10, dump, None)
    plan.check_record(ff)
    plan.check_record(ff)
    assert len(calls) == 2                       # outside: every call checks
    with shared_checks():
        plan.check_record(ff)
        plan.check_record(ff)                    # the flow and the granule stage
        assert len(calls) == 3
        dump.write_bytes(b"<VTKFile>two</VTKFile>")    # same size, new content
        with pytest.raises(DumpReadError, match="SHA-256"):
            plan.check_record(ff)
        with pytest.raises(DumpReadError, match="SHA-256"):
            plan.check_record(ff)                # the kept verdict, the same message
        assert len(calls) == 4
