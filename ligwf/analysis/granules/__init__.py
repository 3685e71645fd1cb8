"""Granules: the bond test and its compiled twin (:mod:`.bonds`), the bridge law
(:mod:`.bridge_law`), the definitions (:mod:`.definitions`: components, CPM communities
(:mod:`.communities`), bridges held through a window (:mod:`.persistent`)), the per-case
frame driver (:mod:`.case`) and the cohesionless controls (:mod:`.controls`,
:mod:`.control_run`, :mod:`.control_verdict`, :mod:`.study_controls`).
"""
