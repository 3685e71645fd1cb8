"""The watchdog process of a runner (``python -m ligwf.engine.watchdog LAUNCHER_PID START
[FOLDER ...]``, started by :func:`ligwf.engine.guard.watch`).

It lives in its own module, above the folder model: stamping the restarts a dead runner
left needs :mod:`ligwf.engine.attempt` and :class:`~ligwf.study.case.CaseFolder`, which
themselves import :mod:`ligwf.engine.guard` (kept at the bottom, with the process
bookkeeping only).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ligwf.engine.attempt import stamp_restarts
from ligwf.engine.guard import RELEASED, engine_tree, stop_engines
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.processes import EngineProcess


def stamp_lost(folders: list[str]) -> None:
    """Identity sidecars for the restarts the dead runner's attempts wrote, in case folders
    or the case folders an ensemble folder's claims name."""
    cases: list[Path] = []
    for folder in map(Path, folders):
        claims = folder / layout.ENSEMBLE_CLAIMS_DIR
        if claims.is_dir():
            for p in claims.glob(layout.ENSEMBLE_CLAIM_GLOB):
                try:
                    cases.append(Path(json.loads(p.read_text())["case"]))
                except (OSError, ValueError, KeyError, TypeError):
                    pass
        else:
            cases.append(folder)
    for path in cases:
        try:
            case = CaseFolder.open(path)
            m = case.manifest()
            if m is not None and m.attempts and m.attempts[-1].ended is None:
                stamp_restarts(case, m.attempts[-1])
        except Exception:  # noqa: BLE001 - the watchdog must never die before its engine
            continue


def main(argv: list[str]) -> int:
    """The watchdog: ``python -m ligwf.engine.guard LAUNCHER_PID START [FOLDER ...]``.
    Waits for the end of stdin, then stops the launcher's engine if it still runs and
    stamps the restarts it left (:func:`stamp_lost`). A runner that released it normally
    has recorded its attempts itself."""
    root = EngineProcess(int(argv[0]), int(argv[1]), "launcher")
    data = sys.stdin.buffer.read()  # returns when the runner closes the pipe or dies
    if data.endswith(RELEASED):
        return 0
    if root.alive():
        stop_engines(engine_tree(root.pid))
    stamp_lost(argv[2:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
