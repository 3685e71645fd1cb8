"""ligwf: coarse-grained LIGGGHTS studies of wet granulation in rotating drums.

The pipeline, one module per stage:
scene -> scaling -> mesh -> render -> (launch) -> dumps -> granules -> gsd/flow -> report.

The public Python API (:mod:`ligwf.api`, see the README's "Python API")::

    import ligwf
    study = ligwf.open_study("runs/demo")
    study.conditions, study.verdict, study.plot_gsd()

This module stays at the bottom layer: importing ``ligwf`` (or any of its stages) loads
no stage; the API's names are imported on first use by the module ``__getattr__`` below,
the one place the package reaches its top layer (``tests/test_architecture.py`` checks
that nothing else does and that ``import ligwf`` loads no stage).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ligwf.errors import LigwfError

if TYPE_CHECKING:   # for type checkers and editors; at run time: __getattr__
    from ligwf.api import MissingOutput, StudyResults, open_study

__version__ = "0.1.0"

#: the public names: these and nothing else are promised to stay
__all__ = ["LigwfError", "MissingOutput", "StudyResults", "__version__", "open_study"]

_LAZY = frozenset({"MissingOutput", "StudyResults", "open_study"})


def __getattr__(name: str):
    """The API's names, imported from :mod:`ligwf.api` when first asked for (so that
    ``import ligwf.scene`` does not load pandas, the report and every stage)."""
    if name in _LAZY:
        from ligwf import api

        value = getattr(api, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'ligwf' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | _LAZY)
