"""Inference: what the measured run values say about CG1, between the analysis (values per
run) and the report (which renders decisions). The criteria of the verdict's budget are a
registry (:mod:`.registry`, the built-in ones in :mod:`.budget`), each deciding one
condition with the statistics of :mod:`.equivalence`, :mod:`.shares` and
:mod:`.field_errors`; :mod:`.criteria` applies Holm's rule over a level, :mod:`.verdict`
gives the study's answer and :mod:`.verdict_records` its one record; :mod:`.sampling`,
:mod:`.planning` and :mod:`.deciding` say what would decide. :mod:`.extrapolation`
estimates a CG1 value from CG-n levels where CG1 cannot run; :mod:`.reference` applies it
to a study's tables."""
