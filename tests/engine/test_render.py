"""Rendering: golden inputs, only what the scene needs, no injection, user overrides."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import yaml

from ligwf.errors import RenderError
from ligwf.engine.render import render
from ligwf.scene.workflow import load_workflow

from helpers import DRUM, ROOT, WET_POLY

sys.path.insert(0, str(ROOT / "scripts"))
from regen_golden import GOLDEN, golden_cases, render_golden  # noqa: E402


@pytest.mark.parametrize("entry", golden_cases(), ids=lambda e: e["name"])
def test_golden(entry):
    expected = (GOLDEN / f"{entry['name']}.in").read_text()
    assert render_golden(entry) == expected, (
        f"rendered input differs from tests/golden/{entry['name']}.in; if the change is "
        "intended run scripts/regen_golden.py and review the diff")


def text(workflow=DRUM, overrides=(), case=0) -> str:
    wf = load_workflow(workflow, list(overrides))
    return render(wf.cases[case].scaled())["in.liggghts"]


def commands(src: str) -> list[str]:
    return [l for l in src.splitlines() if l.strip() and not l.lstrip().startswith("#")]


def test_dry_scene_has_no_liquid():
    src = text(overrides=["scene.liquid.model=none", "scene.analysis.contact_dumps=false",
                          "sweep.rules=[weber]"])
    body = "\n".join(commands(src))
    for word in ("cohesion", "surfaceTension", "fluidViscosity", "contactAngle",
                 "surfaceLiquidContent", "SeparationDistanceRatio"):
        assert word not in body
    assert "pair_style gran model hertz tangential history\n" in src


def test_wet_scene_has_all_six_liquid_properties_spelled_right():
    src = text()
    names = re.findall(r"property/global (\w+)", src)
    for prop in ("surfaceLiquidContentInitial", "surfaceTension", "fluidViscosity",
                 "contactAngle", "minSeparationDistanceRatio", "maxSeparationDistanceRatio"):
        assert names.count(prop) == 1, prop
    assert "cohesion washino/capillary/viscous" in src


def test_no_lifters_mentions_none():
    src = text(overrides=["scene.drum.lifters.count=0"])
    assert "0 lifters" in src


def test_contact_dump_only_with_granules():
    on = "\n".join(commands(text()))
    off = "\n".join(commands(text(overrides=["scene.analysis.contact_dumps=false"])))
    assert "pair/gran/local" in on and "local/gran/vtk" in on
    assert "pair/gran/local" not in off and "local/gran/vtk" not in off and "contacts" not in off


def test_contact_compute_defined_before_first_run_and_dumps_after():
    src = commands(text())
    first_run = next(i for i, l in enumerate(src) if l.startswith("run "))
    assert next(i for i, l in enumerate(src) if "pair/gran/local" in l) < first_run
    assert next(i for i, l in enumerate(src) if l.startswith("dump particles")) > first_run


def test_dumps_are_vtu_and_health_in_thermo():
    src = text()
    assert re.search(r"custom/vtk \d+ post/particles_\*\.vtu", src)
    assert re.search(r"local/gran/vtk \d+ post/contacts_\*\.vtu", src)
    assert ".vtk " not in src
    thermo = next(l for l in src.splitlines() if l.startswith("thermo_style"))
    assert "atoms" in thermo and "f_ts[1]" in thermo and "f_ts[2]" in thermo
    assert "thermo_modify lost warn" in src
    every = int(re.search(r"check/timestep/gran (\d+)", src).group(1))
    assert int(re.search(r"^thermo (\d+)", src, re.M).group(1)) % every == 0


def test_rolling_friction_only_when_set():
    poly = text(WET_POLY)
    assert "rolling_friction cdt" in poly and "coefficientRollingFriction" in poly
    assert "rolling_friction" not in text()


def test_engine_angle_compensated_and_switchable():
    on = text()
    off = text(overrides=["scene.numerics.contact_angle_compensation=false"])
    assert re.search(r"contactAngle peratomtype 58\.63\d* 58\.63", on)
    assert "contactAngle peratomtype 30 30" in off


def test_unsafe_value_refused_even_if_it_bypasses_validation():
    wf = load_workflow(DRUM)
    bad = dataclasses.replace(wf.cases[0].scaled(), name="x\nshell touch /tmp/pwned")
    with pytest.raises(RenderError, match="inject"):
        render(bad)


def test_user_template_folder_overrides_and_strict_undefined(tmp_path):
    scaled = load_workflow(DRUM).cases[0].scaled()
    (tmp_path / "_header.j2").write_text("# site header for {{ s.name }}\natom_style granular\n")
    src = render(scaled, [tmp_path])["in.liggghts"]
    assert src.startswith("# site header for drum-slice\n")
    assert "fix pdd all particledistribution" in src  # the rest still comes from ligwf
    (tmp_path / "_header.j2").write_text("# {{ no_such_value }}\n")
    with pytest.raises(RenderError, match="no_such_value"):
        render(scaled, [tmp_path / "."])


@pytest.mark.parametrize(("flat", "nested"), [
    ("youngs_modulus", "particles.youngs_modulus"), ("dt", "numerics.dt"),
    ("rpm", "drum.rpm"), ("rayleigh_time", "particles.rayleigh_time"),
    ("granules", "contact_dumps"), ("insertion_radius", "fill.radius")])
def test_a_flat_record_name_in_a_user_template_says_where_it_is_now(tmp_path, flat, nested):
    scaled = load_workflow(DRUM).cases[0].scaled()
    assert str(eval(f"s.{nested}", {}, {"s": scaled})) != ""    # the named place exists
    (tmp_path / "_header.j2").write_text(f"# {{{{ s.{flat} }}}}\natom_style granular\n")
    with pytest.raises(RenderError) as err:
        render(scaled, [tmp_path])
    assert str(err.value).endswith(f"(the scaled scene is nested: s.{flat} is s.{nested})")
    (tmp_path / "_header.j2").write_text("# {{ s.no_such_field }}\n")
    with pytest.raises(RenderError) as err:
        render(scaled, [tmp_path])
    assert "nested" not in str(err.value)


def test_render_is_pure(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    files = render(load_workflow(DRUM).cases[1].scaled())
    assert set(files) == {"in.liggghts"}
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_installed_wheel_ships_templates(tmp_path):
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                          str(tmp_path), str(ROOT)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    wheel = next(tmp_path.glob("ligwf-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    shipped = {Path(n).name for n in names if n.startswith("ligwf/templates/")}
    assert {p.name for p in (ROOT / "templates").glob("*.j2")} <= shipped


@pytest.mark.parametrize("axis, grid", [("x", "${ligwf_pa} ${ligwf_pu} 1"),
                                        ("y", "${ligwf_pu} ${ligwf_pa} 1"),
                                        ("z", "${ligwf_pu} 1 ${ligwf_pa}")])
def test_processor_grid_never_cuts_along_gravity(axis, grid):
    # gravity is -z for axes x and y and -y for axis z (Axis.frame); a cut along it
    # would leave the rank above the bed nearly idle
    src = text(overrides=[f"scene.drum.axis={axis}"])
    lines = commands(src)
    assert f"processors {grid}" in lines
    assert lines.index(f"processors {grid}") < next(i for i, l in enumerate(lines)
                                                    if l.startswith("create_box"))
    # run by hand (no -var): every rank along the axis
    assert "variable ligwf_pu index 1" in lines and "variable ligwf_pa index *" in lines


def test_processor_grid_puts_ranks_along_the_axis_first():
    from ligwf.engine.decomposition import MIN_AXIAL_SLAB
    from ligwf.engine.render import grid_vars, processor_grid

    wf = load_workflow(DRUM, ["sweep.cg_levels=[1, 3]", "sweep.rules=[weber]"])
    cg1, cg3 = (c.scaled() for c in wf.cases)
    slabs1 = int(cg1.drum.length / (MIN_AXIAL_SLAB * cg1.d_max))      # 9 mm / 4 mm = 2
    assert slabs1 == 2
    assert processor_grid(cg1, 1) == (1, 1)
    assert processor_grid(cg1, 2) == (1, 2)
    assert processor_grid(cg1, 4) == (2, 2)
    assert processor_grid(cg1, 3) == (3, 1)            # 3 slabs of 3 mm would be too thin
    assert processor_grid(cg3, 2) == (2, 1)            # 9 mm holds one 4 x 3 mm slab only
    for n in range(1, 13):
        across, axial = processor_grid(cg1, n)
        assert across * axial == n and axial <= max(1, slabs1)
    assert grid_vars(cg1, 2) == ["-var", "ligwf_pu", "1", "-var", "ligwf_pa", "2"]
