"""Every kind of batch script rendered for hostile study paths (issue 46 item 1).

A path is data, never script text: each script kind is rendered for study folders named
with ``$(...)``, backticks, quotes, ``;``, ``&&``, ``|``, ``#``, a space, a glob and a
leading ``-`` (inside an absolute path), then

* parsed with ``bash -n``;
* compared line by line with the same script for a plain path: as many lines, each
  starting with the same word (no line the builder did not write);
* each ``#SBATCH`` line read as Slurm reads it (one option; quoting as in a shell, which
  Slurm's parser follows for these characters): ``--output`` is the log path exactly;
* run for real with bash, with a stand-in ``ligwf`` that records its arguments: the study
  path arrives as one argument, unchanged, and no command hidden in it runs.

Paths that cannot be one value of a script (a line break, a carriage return, a tab,
Slurm's ``%`` patterns, a backslash, a relative path) are refused in one line.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
from pathlib import Path, PurePosixPath

import pytest

from ligwf.errors import ConfigError
from ligwf.pipeline.submit_rounds import FollowUp
from ligwf.slurm.script import (ScriptContext, analysis_array_script, analysis_merge_script,
                                analysis_script, array_script)
from ligwf.slurm.site import SlurmSite

HOSTILE_NAMES = [
    "$(touch PWNED)",
    "`touch PWNED`",
    "a'b\"c",
    "x;touch PWNED;y",
    "-rf",
    "a && touch PWNED",
    "a|touch PWNED",
    "#not a comment",
    "with space",
    "*",
    "${HOME}~",
    "a>PWNED",
]
TOKEN = "0123abcd4567"


def _fake_ligwf(folder: Path) -> Path:
    """A ``ligwf`` that appends its arguments to $ARGV_LOG (fields split by US, calls by RS)."""
    fake = folder / "fake-ligwf"
    fake.write_text("#!/bin/sh\nfor a in \"$@\"; do printf '%s\\037' \"$a\" >> \"$ARGV_LOG\"; "
                    "done\nprintf '\\036' >> \"$ARGV_LOG\"\n")
    fake.chmod(0o755)
    return fake


def _calls(log: Path) -> list[list[str]]:
    text = log.read_text() if log.exists() else ""
    return [call.split("\x1f")[:-1] for call in text.split("\x1e")[:-1]]


def _scripts(study: PurePosixPath, site: SlurmSite, mesh_cache: str) -> dict[str, str]:
    """Every script kind for ``study`` (the follow-up job of a sequential study included,
    its mesh cache path hostile too)."""
    ctx = ScriptContext(study, "ligwf-demo", "0.0.0-test")
    follow = FollowUp("slurm", mesh_cache=Path(mesh_cache)).steps
    return {"array": array_script(ctx, site, [0, 1]),
            "analysis": analysis_script(ctx, site, ["analyse", "report"]),
            "follow-up": analysis_script(ctx, site, follow),
            "analysis-array": analysis_array_script(ctx, site, 2, TOKEN),
            "analysis-merge": analysis_merge_script(ctx, site, 2, TOKEN, ["report"])}


def _expected_calls(kind: str, study: str, mesh_cache: str) -> list[list[str]]:
    return {"array": [["run-case", study, "--index", "0", "--np", "1"]],
            "analysis": [["analyse", study], ["report", study]],
            "follow-up": [["slurm", "next-round", "--mesh-cache", mesh_cache, study]],
            "analysis-array": [["analyse", study, "--part", "0/2", "--token", TOKEN]],
            "analysis-merge": [["analyse", study, "--merge", "2", "--token", TOKEN],
                               ["report", study]]}[kind]


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_a_hostile_study_path_stays_one_value_in_every_script(name, tmp_path):
    bash = shutil.which("bash")
    assert bash is not None
    fake = _fake_ligwf(tmp_path)
    site = SlurmSite(ligwf=str(fake), partition="compute", time="00:10:00")
    study = tmp_path / "studies" / name / "study"
    plain = tmp_path / "studies" / "plain" / "study"
    for folder in (study, plain):
        folder.mkdir(parents=True)
    cache = str(tmp_path / "caches" / name)
    hostile = _scripts(PurePosixPath(study), site, cache)
    reference = _scripts(PurePosixPath(plain), site, str(tmp_path / "caches" / "plain"))
    for kind, text in hostile.items():
        check = subprocess.run([bash, "-n"], input=text, text=True, capture_output=True)
        assert check.returncode == 0, f"{kind}: bash -n: {check.stderr}\n{text}"
        lines, meant = text.splitlines(), reference[kind].splitlines()
        assert len(lines) == len(meant), f"{kind}: {len(lines)} lines, meant {len(meant)}\n{text}"
        for line, want in zip(lines, meant):
            assert line.split(" ", 1)[0] == want.split(" ", 1)[0], (kind, line, want)
        for line in (ln for ln in lines if ln.startswith("#SBATCH ")):
            words = shlex.split(line[len("#SBATCH "):])
            assert len(words) == 1 and words[0].startswith("--"), (kind, line)
            if words[0].startswith("--output="):
                log = words[0].removeprefix("--output=")
                assert log.startswith(f"{study}/slurm/logs/ligwf-demo_"), (kind, log)
        argv_log = tmp_path / f"argv-{kind}.log"
        env = {"PATH": os.environ["PATH"], "ARGV_LOG": str(argv_log), "HOME": str(tmp_path),
               "SLURM_ARRAY_TASK_ID": "0", "SLURM_ARRAY_JOB_ID": "7"}
        ran = subprocess.run([bash, "-c", text, "script"], env=env, cwd=tmp_path, text=True,
                             capture_output=True, timeout=30)
        assert ran.returncode == 0, f"{kind}: {ran.stderr}"
        assert _calls(argv_log) == _expected_calls(kind, str(study), cache), kind
    assert not [p for p in tmp_path.rglob("PWNED")], "a command hidden in a path ran"


@pytest.mark.parametrize("path,why", [
    ("/scratch/s\ntouch PWNED\n#", "line break"),
    ("/scratch/s\rx", "carriage return"),
    ("/scratch/s\tx", "tab"),
    ("/scratch/%x-study", "percent sign"),
    ("/scratch/a\\b", "backslash"),
    ("-rf/study", "not an absolute path"),
    ("scratch/study", "not an absolute path"),
    ("/" + "a" * 300, "NAME_MAX"),
])
def test_a_path_that_cannot_be_one_value_is_refused_in_one_line(path, why):
    with pytest.raises(ConfigError, match=why) as info:
        ScriptContext(PurePosixPath(path), "ligwf-demo", "0.0.0-test")
    assert "\n" not in str(info.value) and "study folder" in str(info.value)


def test_job_names_tokens_and_steps_are_checked():
    site = SlurmSite(ligwf="ligwf")
    with pytest.raises(ConfigError, match="job name"):
        ScriptContext(PurePosixPath("/s"), "ligwf-a\n#SBATCH --x", "0")
    ctx = ScriptContext(PurePosixPath("/s"), "ligwf-a", "0")
    with pytest.raises(ConfigError, match="staging token"):
        analysis_array_script(ctx, site, 2, "x; touch PWNED")
    with pytest.raises(ConfigError, match="line break"):
        analysis_script(ctx, site, ["report\ntouch PWNED"])
