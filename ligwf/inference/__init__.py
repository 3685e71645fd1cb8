"""Inference: what the measured run values say about CG1, between the analysis (values per
run) and the report (which renders decisions). :mod:`.extrapolation` estimates a CG1 value
from CG-n levels where CG1 cannot run; :mod:`.reference` applies it to a study's tables."""
