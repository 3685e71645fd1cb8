"""Names in ligwf/ that no code of the repository calls, yet are used: the entry points
Python itself calls, read by vulture in tests/test_seams.py (never imported or run).
Add a name here only with the reason it is alive."""

# ligwf/__init__.py: module __getattr__ imports the API lazily (``from ligwf import
# open_study``); module __dir__ lists those lazy names for dir() and completion
__getattr__  # noqa: B018
__dir__  # noqa: B018

# ligwf/engine/site.py _identify(executable, ld_library_path): the loader path is part of
# the lru_cache key (a changed LD_LIBRARY_PATH identifies the engine again), not read inside
ld_library_path  # noqa: B018
