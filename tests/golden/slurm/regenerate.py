"""Golden references of ligwf's Slurm batch scripts: the cases and their regeneration.

Each entry of :data:`CASES` renders one script from fixed inputs with the pure builders of
``ligwf.slurm.script``; ``tests/slurm/test_slurm_golden.py`` diffs them against the ``.sh``
files next to this one. After a deliberate change of the scripts, regenerate and review
the diff::

    .venv/bin/python tests/golden/slurm/regenerate.py && git diff tests/golden/slurm
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath
from typing import Callable

from ligwf.slurm.script import ScriptContext, analysis_script, array_script
from ligwf.slurm.site import SlurmSite

HERE = Path(__file__).resolve().parent
STUDY = PurePosixPath("/scratch/alice/drum-study")
LIGWF = "/opt/ligwf/venv/bin/ligwf"
VERSION = "0.0.0-golden"

MINIMAL = SlurmSite(ligwf=LIGWF)
FULL = SlurmSite(partition="compute", account="proj-42", time="1-02:00:00", ntasks=4,
                 max_concurrent=8, modules=("openmpi/4.1", "liggghts/3.8.0"),
                 setup=("source /opt/ligwf/venv/bin/activate", "ulimit -c 0"),
                 launcher="srun --mpi=pmix", ligwf=LIGWF,
                 sbatch_args=("--mem-per-cpu=2G", "--constraint=avx2"),
                 analysis_time="00:30:00")


#: a paper-scale case planned on 119 ranks, 64 cores a node: 2 nodes, OpenMPI's mpirun
TWO_NODES = SlurmSite(partition="compute", time="12:00:00", ntasks=119, cores_per_node=64,
                      launcher="mpirun", ligwf=LIGWF,
                      setup=("export OMPI_MCA_btl_tcp_if_include=10.0.0.0/8",))


def _array(site: SlurmSite, indices: list[int], nodes: int | None = None) -> str:
    return array_script(ScriptContext(STUDY, "ligwf-drum-study", VERSION), site, indices,
                        nodes)


def _analysis(site: SlurmSite, steps: list[str]) -> str:
    return analysis_script(ScriptContext(STUDY, "ligwf-drum-study-analysis", VERSION), site,
                           steps)


CASES: dict[str, Callable[[], str]] = {
    "array_minimal.sh": lambda: _array(MINIMAL, [0, 1, 2, 3]),
    "array_full_site.sh": lambda: _array(FULL, list(range(36))),
    "array_resubmit.sh": lambda: _array(SlurmSite(ligwf=LIGWF, max_concurrent=2, time="30"),
                                        [1, 4, 5, 6, 9]),
    "array_two_nodes.sh": lambda: _array(TWO_NODES, [0], nodes=2),
    "analysis_minimal.sh": lambda: _analysis(MINIMAL, ["analyse"]),
    "analysis_full_site.sh": lambda: _analysis(FULL, ["analyse", "report"]),
}


def main() -> None:
    for name, make in CASES.items():
        (HERE / name).write_text(make())
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
