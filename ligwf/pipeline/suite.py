"""The stability stress suite (``ligwf stability-suite``): every variant of a suite file
prepared and written as a study folder of its own, refused cases included (that is the
point: the suite checks the pre-flight's verdicts against what the engine then does,
``ligwf stability-report``)."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Iterator

from ligwf.fsio import atomic_write_json
from ligwf.pipeline.prepare import Prepared, prepare, write
from ligwf.scene.stability_suite import load_suite
from ligwf.study.layout import SUITE_RECORD



def write_suite(suite: Path, out: Path, template_dirs: Iterable[Path] = (),
                mesh_cache: Path | None = None) -> Iterator[tuple[str, Prepared]]:
    """Prepare (pre-flight verdicts kept, refusals let through) and write each variant of
    ``suite`` into ``out/<variant>``, yielding it once written; the suite record follows
    the last one."""
    variants = load_suite(suite)
    dirs = tuple(template_dirs)
    for variant, wf in variants.items():
        prepared = prepare(wf, dirs, allow_unstable=True)
        write(prepared, out / variant, mesh_cache)
        yield variant, prepared
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / SUITE_RECORD, {"suite": str(suite), "variants": list(variants)})
