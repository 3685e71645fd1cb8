"""``python -m ligwf``: the ``ligwf`` command, for runners that start ligwf from the same
interpreter (:meth:`ligwf.local.LocalExecutor.analyse` runs its analysis shares so)."""

from ligwf.cli.main import main

raise SystemExit(main())
