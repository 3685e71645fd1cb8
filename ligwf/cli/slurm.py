"""``ligwf slurm submit | status | resubmit``: run a study as Slurm job arrays.

``submit`` renders every case (the same folders ``ligwf render`` writes), writes one array
script with one task per case (each runs ``ligwf run-case STUDY --index I``, the local
runner with its manifests, health checks and resume) plus an analysis job that depends on
the array (``afterany``), and submits both. ``--dry-run`` prints the scripts and the sbatch
commands and writes nothing. ``status`` joins the runner's manifests with squeue/scontrol;
``resubmit`` submits a new array with exactly the cases that are missing, failed or killed.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from rich.table import Table

from ligwf.study.prepare import render_workflow, write_study
from ligwf.cli.main import add_workflow_args, case_table, console, err_console
from ligwf.errors import SubmitError
from ligwf.slurm.jobs import (active_tasks, require_scheduler, cases_to_resubmit, dry_run_text, next_round, plan_jobs,
                    read_record, read_study, recorded_site, study_status, submit_jobs)
from ligwf.slurm.site import SlurmSite, load_slurm_site
from ligwf.scene.workflow import load_workflow

#: ligwf sub-commands the analysis job runs over the study, in order, when they exist.
ANALYSIS_STEPS = ("analyse", "report")

_subparsers: argparse._SubParsersAction | None = None


def analysis_steps() -> list[str]:
    """The post-processing commands this ligwf installation has (``analyse``, ``report``).

    ``analyse`` is always included: it is the documented interface of the analysis stage,
    and a job that fails for want of it is more honest than a silently missing analysis.
    """
    have = set(_subparsers.choices) if _subparsers is not None else set()
    steps = [s for s in ANALYSIS_STEPS if s in have]
    if "analyse" not in steps:
        err_console.print("[yellow]warning:[/] this ligwf has no 'analyse' command yet; the "
                          "analysis job will run 'ligwf analyse' and fail until it exists")
        steps.insert(0, "analyse")
    return steps


def add_site_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--partition", help="Slurm partition (default: site setting)")
    p.add_argument("--account", help="Slurm account (default: site setting)")
    p.add_argument("--time", help="wall time per case, e.g. 02:00:00 (default: site setting)")
    p.add_argument("--ntasks", type=int, help="MPI ranks per case (default: site setting or 1)")
    p.add_argument("--max-concurrent", type=int, metavar="K",
                   help="at most K cases at once (--array=...%%K)")
    p.add_argument("--no-analysis", action="store_true",
                   help="do not submit the dependent analysis job")
    p.add_argument("--dry-run", action="store_true",
                   help="print the scripts and sbatch commands; submit and write nothing")


def site_from_args(args: argparse.Namespace, base: SlurmSite) -> SlurmSite:
    return base.with_overrides(partition=args.partition, account=args.account, time=args.time,
                               ntasks=args.ntasks, max_concurrent=args.max_concurrent)


def _site_from_record(values: dict[str, Any]) -> SlurmSite:
    names = {f.name for f in fields(SlurmSite)}
    return SlurmSite(**{k: tuple(v) if isinstance(v, list) else v
                        for k, v in values.items() if k in names})


def _print_submitted(entries: list[dict]) -> None:
    for e in entries:
        dep = f" (after {e['after']})" if e.get("after") else ""
        console.print(f"submitted {e['kind']} job {e['job_id']}{dep}: {e['script']}")


def cmd_submit(args: argparse.Namespace) -> int:
    wf = load_workflow(args.workflow, args.overrides)
    rendered = render_workflow(wf, args.templates)
    site = site_from_args(args, load_slurm_site())
    steps = [] if args.no_analysis else analysis_steps()
    out: Path = args.out.resolve()
    round_no = next_round(out) if (out / "slurm").is_dir() else 1
    jobs = plan_jobs(out, wf.name, site, [rc.case.index for rc in rendered], steps, round_no)
    if args.dry_run:
        console.print(case_table(rendered, f"{wf.name}: {len(rendered)} case(s) (dry run)"))
        print(dry_run_text(jobs))
        return 0
    require_scheduler()
    if read_record(out):
        busy = active_tasks(study_status(out).cases)
        if busy:
            raise SubmitError(f"{out} still has {len(busy)} queued or running case(s) "
                              f"({', '.join(c.job or '?' for c in busy[:5])}); wait, scancel "
                              "them, or use 'ligwf slurm resubmit'")
    write_study(wf, rendered, out, args.mesh_cache)
    console.print(case_table(rendered, f"{wf.name}: {len(rendered)} case(s) -> {out}"))
    _print_submitted(submit_jobs(out, jobs, site))
    return 0


def status_table(study_dir: Path) -> tuple[Table, dict]:
    st = study_status(study_dir, tolerant=True)
    table = Table(title=f"{study_dir}")
    for col in ("index", "case", "manifest", "slurm task", "slurm state", "reason"):
        table.add_column(col)
    counts: dict[str, int] = {}
    for c in st.cases:
        counts[c.manifest] = counts.get(c.manifest, 0) + 1
        table.add_row(str(c.index), c.case_id, c.manifest, c.job or "-", c.slurm_state or "-",
                      c.reason[:60])
    data = {"cases": [asdict(c) for c in st.cases], "jobs": st.jobs, "counts": counts,
            "scheduler_error": st.scheduler_error}
    return table, data


def cmd_status(args: argparse.Namespace) -> int:
    table, data = status_table(args.study_dir)
    if args.json:
        print(json.dumps(data, indent=2, default=str))
        return 0
    console.print(table)
    if data["scheduler_error"]:
        err_console.print(f"[yellow]Slurm not reachable, manifests only:[/] "
                          f"{data['scheduler_error']}", highlight=False)
    for job in data["jobs"]:
        if job["kind"] != "array":
            console.print(f"{job['kind']} job {job['job_id']} (after {job.get('after')}): "
                          f"{job.get('state') or 'finished/forgotten by Slurm'}")
    console.print(", ".join(f"{n} {s}" for s, n in sorted(data["counts"].items())))
    return 0


def cmd_resubmit(args: argparse.Namespace) -> int:
    study_dir: Path = args.study_dir.resolve()
    study = read_study(study_dir)
    recorded = recorded_site(study_dir)
    base = _site_from_record(recorded) if recorded else load_slurm_site()
    site = site_from_args(args, base)
    st = study_status(study_dir)
    indices = cases_to_resubmit(st.cases, args.include_unstable)
    busy = active_tasks(st.cases)
    if busy:
        console.print(f"{len(busy)} case(s) still queued or running, not resubmitted: "
                      + ", ".join(c.job or "?" for c in busy))
    if not indices:
        console.print("nothing to resubmit: every case is done, unstable or still queued")
        return 0
    steps = [] if args.no_analysis else analysis_steps()
    jobs = plan_jobs(study_dir, study.get("name", "study"), site, indices, steps,
                     next_round(study_dir))
    console.print(f"resubmitting {len(indices)} case(s): "
                  + ", ".join(f"{c.index} {c.case_id} ({c.manifest})"
                              for c in st.cases if c.index in indices))
    if args.dry_run:
        print(dry_run_text(jobs))
        return 0
    _print_submitted(submit_jobs(study_dir, jobs, site))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``ligwf slurm submit|status|resubmit`` to the top-level parser."""
    global _subparsers
    _subparsers = subparsers
    slurm = subparsers.add_parser("slurm", help="run a study as Slurm job arrays")
    sub = slurm.add_subparsers(dest="slurm_command", required=True)

    p = sub.add_parser("submit", help="render all cases and submit them as one job array "
                                      "plus a dependent analysis job")
    add_workflow_args(p)
    p.add_argument("--out", type=Path, required=True, help="study folder to write")
    p.add_argument("--mesh-cache", type=Path, default=None,
                   help="mesh cache folder (default $LIGWF_MESH_CACHE or ./meshes)")
    add_site_args(p)
    p.set_defaults(func=cmd_submit)

    p = sub.add_parser("status", help="cases with their manifest and Slurm state")
    p.add_argument("study_dir", type=Path, help="study folder")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=cmd_status)

    p = sub.add_parser("resubmit", help="submit a new array with exactly the cases that are "
                                        "missing, failed or killed")
    p.add_argument("study_dir", type=Path, help="study folder")
    p.add_argument("--include-unstable", action="store_true",
                   help="also rerun cases the health checks marked unstable")
    add_site_args(p)
    p.set_defaults(func=cmd_resubmit)
