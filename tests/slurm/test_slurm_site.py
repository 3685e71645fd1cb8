"""Slurm site settings: YAML + LIGWF_SLURM_* + command line, validated before scripting."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from ligwf.errors import ConfigError
from ligwf.slurm.site import (SlurmSite, default_ligwf_command, load_slurm_site,
                              merged_settings, ntasks_configured, site_from_mapping)


def test_env_overrides_site_file(tmp_path, monkeypatch):
    site = tmp_path / "site.yaml"
    site.write_text("slurm:\n  partition: compute\n  account: proj1\n  ntasks: 4\n"
                    "  modules: [openmpi/4.1, liggghts/3.8.0]\n  max_concurrent: 3\n"
                    "  sbatch_args: [--mem=4G]\n")
    monkeypatch.setenv("LIGWF_SITE", str(site))
    env = {"LIGWF_SLURM_PARTITION": "short", "LIGWF_SLURM_MODULES": "a/1,b/2"}
    s = load_slurm_site(env)
    assert s.partition == "short" and s.account == "proj1" and s.ntasks == 4
    assert s.modules == ("a/1", "b/2") and s.max_concurrent == 3
    assert s.sbatch_args == ("--mem=4G",)


def test_command_line_wins_and_none_keeps_site():
    s = SlurmSite(partition="compute", ntasks=4)
    t = s.with_overrides(partition=None, ntasks=1, time="00:10:00")
    assert (t.partition, t.ntasks, t.time) == ("compute", 1, "00:10:00")


def test_default_ligwf_is_the_running_venv():
    cmd = default_ligwf_command()
    assert cmd == str(Path(sys.executable).parent / "ligwf")
    assert site_from_mapping({}).ligwf == cmd


def test_sbatch_args_from_env_text():
    s = site_from_mapping(merged_settings({}, {"LIGWF_SLURM_SBATCH_ARGS": "--mem=4G --qos=low"}))
    assert s.sbatch_args == ("--mem=4G", "--qos=low")


@pytest.mark.parametrize("values,needle", [
    ({"partition": "a;rm -rf /"}, "partition"),
    ({"account": "x\ny"}, "account"),
    ({"time": "2 hours"}, "time"),
    ({"ntasks": 0}, "ntasks"),
    ({"ntasks": "four"}, "ntasks"),
    ({"max_concurrent": 0}, "max_concurrent"),
    ({"modules": ["ok/1", "bad module"]}, "module"),
    ({"setup": ["echo a\necho b"]}, "setup"),
    ({"sbatch_args": ["-p x"]}, "sbatch_args"),
    ({"launcher": "  "}, "launcher"),
    ({"partiton": "typo"}, "unknown key"),
])
def test_invalid_settings_are_config_errors(values, needle):
    with pytest.raises(ConfigError, match=needle):
        site_from_mapping(values)


@pytest.mark.parametrize("time", ["30", "30:00", "01:00:00", "2-0", "2-12:00", "1-02:00:00"])
def test_slurm_time_formats(time):
    assert SlurmSite(time=time).time == time


def test_site_slurm_block_must_be_mapping():
    with pytest.raises(ConfigError):
        merged_settings({"slurm": ["partition"]}, {})


def test_ntasks_set_in_the_site_file_or_environment_overrides_the_rank_plan(tmp_path,
                                                                           monkeypatch):
    site = tmp_path / "site.yaml"
    site.write_text("slurm:\n  partition: compute\n")
    monkeypatch.setenv("LIGWF_SITE", str(site))
    assert not ntasks_configured({})
    assert ntasks_configured({"LIGWF_SLURM_NTASKS": "4"})
    site.write_text("slurm:\n  ntasks: 2\n")
    assert ntasks_configured({})
