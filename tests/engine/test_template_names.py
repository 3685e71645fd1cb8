"""The engine templates spell the file names the engine writes (periodic restarts, particle
and contact dumps); ligwf finds them by the names in study/layout.py. This test holds the
two together: every restart and dump line of every template names a layout name."""

from __future__ import annotations

import re

import pytest

from ligwf.study import layout

from helpers import ROOT

TEMPLATES = sorted((ROOT / "templates").glob("*.j2"))
#: a periodic restart line (its last two words: the files) and a dump line (its file: the
#: word with a ``*``, where the engine puts the step); Jinja expressions may hold spaces
RESTART = re.compile(r"^\s*restart\s.*\s(\S+)\s+(\S+)\s*$")
DUMP = re.compile(r"^\s*dump\s.*?\s(\S*\*\S*)")


def name_problems(text: str) -> list[str]:
    """Restart and dump lines of a template that do not name what layout.py names."""
    bad = []
    for line in text.splitlines():
        if m := RESTART.match(line):
            if (m[1], m[2]) != layout.PERIODIC_RESTARTS:
                bad.append(f"restart files {m[1]}, {m[2]} (layout: {layout.PERIODIC_RESTARTS})")
        elif m := DUMP.match(line):
            folder, _, name = m[1].rpartition("/")
            example = name.replace("*", "123")
            if folder != layout.POST_DIR or not (layout.PARTICLE_DUMP_RE.match(example)
                                                 or layout.CONTACT_DUMP_RE.match(example)):
                bad.append(f"dump file {m[1]} (layout: {layout.POST_DIR}/ and "
                           f"{layout.PARTICLE_DUMP_RE.pattern} or {layout.CONTACT_DUMP_RE.pattern})")
    return bad


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda p: p.name)
def test_templates_name_the_layouts_files(template):
    assert not name_problems(template.read_text())


def test_the_templates_write_restarts_and_both_dumps():
    text = "\n".join(t.read_text() for t in TEMPLATES)
    assert any(RESTART.match(line) for line in text.splitlines())
    dumps = [DUMP.match(l)[1] for l in text.splitlines() if DUMP.match(l)]
    assert any("particles_" in d for d in dumps) and any("contacts_" in d for d in dumps)


def test_a_renamed_file_is_seen():
    assert name_problems("restart 100 restart/a.liggghts restart/restart_b.liggghts")
    assert name_problems("dump particles all custom/vtk 10 post/atoms_*.vtu id type x y z")
    assert name_problems("dump contacts all local/gran/vtk 10 dumps/contacts_*.vtu contacts")
    assert not name_problems("dump contacts all local/gran/vtk 10 post/contacts_*.vtu contacts")
