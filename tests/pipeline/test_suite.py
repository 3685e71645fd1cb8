"""The stress suite is written variant by variant, refused cases included, then its record."""

from __future__ import annotations

import json

from ligwf.pipeline.suite import write_suite
from ligwf.study.layout import SUITE_RECORD
from ligwf.scene.stability import REFUSED
from ligwf.scene.stability_suite import load_suite
from ligwf.study.layout import is_case_folder, is_study_folder

from helpers import ROOT

SUITE = ROOT / "workflows" / "stability.yaml"


def test_every_variant_is_written_refused_ones_too_and_the_record_comes_last(tmp_path,
                                                                            monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "suite"
    written = write_suite(SUITE, out)
    variant, prepared = next(written)
    assert is_study_folder(out / variant) and not (out / SUITE_RECORD).exists()
    rest = list(written)
    names = [variant] + [v for v, _ in rest]
    assert names == list(load_suite(SUITE))
    verdicts = [rep.verdict for _, p in [(variant, prepared), *rest] for rep in p.preflight]
    assert REFUSED in verdicts            # the suite's point: refused cases are run too
    for name, p in [(variant, prepared), *rest]:
        assert all(is_case_folder(out / name / rc.case.case_id) for rc in p.rendered)
    assert json.loads((out / SUITE_RECORD).read_text()) == {"suite": str(SUITE),
                                                             "variants": names}
