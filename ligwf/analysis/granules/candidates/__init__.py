r"""Candidate granule definitions measured against the acceptance criteria (a)-(e): the
measurement of docs/results/granule_definitions.md, in modules: a case's frames and
bridges (:mod:`.frames`), bond graphs cut into granules (:mod:`.graphs`), the candidates
(:mod:`.specs`), the criteria (:mod:`.criteria`); ``python -m`` runs it (:mod:`.__main__`).

Run (the cases are ligwf case folders: a scene record and ``post/`` dumps)::

    .venv/bin/python -m ligwf.analysis.granules.candidates \
        --base CG1_CASE_AT_THE_REFERENCE_CONDITION \
        --series CG1_CASE_LOW CG1_CASE_MID CG1_CASE_HIGH \
        --cg-series CGn_CASE_LOW CGn_CASE_MID CGn_CASE_HIGH \
        [--tiles 2 4] [--steady 0.25] [--boot 1000] [--speed-tiles 1 4 16]

The measurement of docs/results/granule_definitions.md (cases of ``ligwf run
workflows/granules.yaml --out /tmp/gd/lc --np 2 --set "sweep.cg_levels=[1,2]" --set
"sweep.rules=[weber]" --set sweep.replicas=1 --set scene.numerics.dump_interval=0.02 --set
scene.process.run_time=1.5 --set "sweep.scene.liquid.liquid_content=[0.01,0.02,0.04]"``)::

    L=/tmp/gd/lc; .venv/bin/python -m ligwf.analysis.granules.candidates \
        --base $L/cg1-none-r0_liquid_content-0.02 \
        --series $L/cg1-none-r0_liquid_content-0.0{1,2,4} \
        --cg-series $L/cg2-weber-r0_liquid_content-0.0{1,2,4} --speed-tiles 1 4 16

Needs python-igraph and leidenalg in the venv (``pip install python-igraph leidenalg``).
``--base`` gives (a), (b), (c) and the speed table; ``--series`` (three liquid contents or
fill levels of one scene, in process order) gives (d); ``--cg-series`` (the same three
conditions at CG level n, We-scaled) gives (e) against ``--series``.

Definitions used (see docs/results/granule_definitions.md):

* bridge: a dumped pair whose washino/easo capillary force (ligwf.liquids.bridges, from
  the dumped overlap) is > 0;
* relative bridge force f_rel = F / (2 pi R* gamma cos theta), the force over the force of a
  touching bridge of the same pair: dimensionless, the same under every CG rule;
* velocity frames: ``lab``; ``rot`` = v - omega x r (the drum's rigid rotation, axis and
  omega from the case's scene record, centre on the axis through the origin); ``flow`` = v minus the
  mean velocity of the particles within 3 particle diameters (periodic along the axis);
* persistence k: the bond (with its force/angle filter) holds in k successive dumps;
* partitions: ``cc`` connected components, ``louvain`` (networkx, resolution 1),
  ``leiden`` (igraph Leiden, modularity, resolution 1), ``cpm`` (igraph Leiden, constant
  Potts model with resolution gamma; edge weight f_rel * n^2 and node weight n^3 at CG level
  n, which keeps the granule volume scale of CPM CG-neutral);
* a granule percolates when it closes a cycle around the periodic axis;
* d50: volume-weighted median of the volume-equivalent diameters (physical volume, m^3,
  NOT divided by n^3) of granules with >= 2 particles; for (e) also with a common cut
  (granules >= 2 particles of the coarsest level, at every level); bands: 95 % bootstrap over steady
  frames (frames resampled with replacement);
* steady frames: dumps after the first ``--steady`` fraction of production (production
  starts at the first dump: ligwf defines the dumps after the settle runs).
"""
