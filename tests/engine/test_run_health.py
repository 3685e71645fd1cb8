"""Health checks, thermo parsing, manifests and resume planning (no engine)."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import pytest

from ligwf.engine.health import (Expectation, assess, engine_signal, atom_loss, insertion_shortfall,
                          kinetic_energy_blowup, kinetic_energy_ceiling, log_errors,
                          log_warnings, non_finite, verdict)
from ligwf.study.manifest import Manifest, read_manifest, write_manifest
from ligwf.engine.resume import phase_steps_between, resume_phase
from ligwf.engine.thermo import parse_screen
from ligwf.study.thermo_table import ThermoRow, rows_from_csv, rows_to_csv

# A screen in the shape LIGGGHTS 3.8.0 prints it (header, rows, "Loop time", markers).
SCREEN = """LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled 2022-01-26-19:42:32 by buildd, git commit unknown)
ligwf-phase fill 1
    Step           Time    Atoms         KinEng            rke          ts[1]          ts[2]            CPU 
       0              0        0              0              0              0              0              0 
insertion: proc 0 at 10 %
     170   0.0049933408      182  8.4302586e-06  9.4004216e-09           0.16    0.039071116    0.006204117 
     340   0.0099866817      182   3.102742e-05  1.8575826e-08           0.16    0.042148945    0.016134749 
Loop time of 0.5 on 2 procs for 340 steps with 182 atoms, finish time Sat Nov 21 23:19:17 2026
ligwf-phase settle
    Step           Time    Atoms         KinEng            rke          ts[1]          ts[2]            CPU 
     340   0.0099866817      182   3.102742e-05  1.8575826e-08           0.16    0.042148945              0 
     510    0.014980023      180           -nan  6.3177675e-08           0.16    0.044317891    0.028598397 
"""


def rows(*triples):
    return [ThermoRow(step, {"step": step, "atoms": atoms, "ke": ke, "rke": 0.0}, "p")
            for step, atoms, ke in triples]


def test_parse_screen_rows_phases_and_timing():
    p = parse_screen(SCREEN)
    assert [r.step for r in p.rows] == [0, 170, 340, 510]
    assert p.rows[2].phase == "settle"  # the repeated first row of a run replaces the old one
    assert math.isnan(p.rows[3].get("ke"))
    assert p.phase_walls() == {"fill": 0.5, "settle": 0.028598397}
    assert p.phase_steps() == {"fill": 340, "settle": 170}


def test_thermo_csv_round_trip():
    p = parse_screen(SCREEN)
    back = rows_from_csv(rows_to_csv(p.rows))
    assert [r.step for r in back] == [0, 170, 340, 510]
    assert back[1].get("atoms") == 182 and back[3].phase == "settle"


def test_each_signature_is_found():
    p = parse_screen(SCREEN)
    assert non_finite(p.rows)[0].step == 510
    assert atom_loss(p.rows)[0].step == 510
    assert atom_loss(rows((0, 0, 0), (10, 50, 1), (20, 100, 1))) == []  # insertion is growth
    # the top-up wave places a few extra particles and trims them to the target one step
    # later: not a loss with the target known, but a fall below the target still is
    topup = rows((0, 0, 0), (10, 90, 1), (11, 116, 1), (12, 100, 1), (20, 100, 1))
    assert atom_loss(topup, target=100) == []
    assert atom_loss(topup)[0].step == 12
    assert atom_loss(topup + rows((30, 99, 1)), target=100)[0].step == 30
    lines = ["  100 1 2 3 4", "WARNING: time-step is  35.2 % of rayleigh time",
             "WARNING: Lost atoms: original 222 current 220", "ERROR: Unknown command: x (a:1)"]
    kinds = {i.kind for i in log_warnings(lines)}
    assert kinds == {"timestep_warning", "lost_atoms"}
    err = log_errors(lines)
    assert err[0].message.startswith("ERROR: Unknown command") and err[0].step == 100
    abort = log_errors(["MPI_ABORT was invoked on rank 0 in communicator MPI_COMM_WORLD"])
    assert abort and abort[0].kind == "error"


def test_kinetic_energy_blowup_ignores_drum_start_but_not_a_blowup():
    ceiling = kinetic_energy_ceiling(mass=0.01, drum_diameter=0.05, omega=3.14)
    assert ceiling == pytest.approx(0.01 * 9.81 * 0.05 + 0.5 * 0.01 * (3.14 * 0.025) ** 2)
    start_up = rows((0, 200, 4e-10), (10, 200, 1e-5), (20, 200, 1.2e-5))  # x25000, physical
    assert kinetic_energy_blowup(start_up, ceiling) == []
    blown = rows((0, 200, 1e-5), (10, 200, 2e-5), (20, 200, 50 * ceiling))
    assert kinetic_energy_blowup(blown, ceiling)[0].step == 20
    jump = rows((0, 200, 1e-3 * ceiling), (10, 200, 2e-3 * ceiling), (20, 200, 5.0 * ceiling))
    assert kinetic_energy_blowup(jump, ceiling)[0].step == 20


def test_insertion_shortfall_only_at_end_of_settling():
    assert insertion_shortfall(rows((0, 0, 0), (100, 80, 1)), 84, 100)[0].step == 100
    assert insertion_shortfall(rows((0, 0, 0), (50, 80, 1)), 84, 100) == []
    assert insertion_shortfall(rows((0, 0, 0), (100, 84, 1)), 84, 100) == []


def test_verdict_order():
    exp = Expectation(182, 340, 1000, None)
    issues = assess(parse_screen(SCREEN).rows, SCREEN.splitlines(), exp)
    assert verdict(issues, 0, 510, 1000)[0] == "unstable"
    assert verdict([], 0, 1000, 1000) == ("done", "finished: all 1000 steps")
    assert verdict([], 0, 500, 1000, killed=True)[0] == "killed"
    assert verdict([], 1, 500, 1000)[0] == "failed"
    assert verdict([], 0, 500, 1000)[0] == "failed"  # exit 0 but short: not success


def test_a_task_killed_from_outside_is_a_stop_and_a_crash_is_not():
    """mpirun's and srun's notices and the launchers' 128 + signal exit codes: a rank killed
    by SIGKILL/SIGTERM (the OOM killer, a user, a lost node's slurmstepd) makes the case
    ``killed`` (resumable from its own restart); a segfault stays a crash (``failed``)."""
    mpirun = ["mpirun noticed that process rank 1 with PID 0 on node n1 exited on signal 9 (Killed)."]
    srun = ["srun: error: ligwf-n2: task 1: Killed", "srun: Terminating StepId=12.0"]
    assert engine_signal(mpirun, 137) == 9 and engine_signal(srun, 137) == 9
    assert engine_signal(["srun: error: n3: tasks 0-1: Terminated"], 143) == 15
    assert engine_signal([], 137) == 9 and engine_signal([], -15) == 15
    assert engine_signal(["srun: error: n2: task 0: Segmentation fault"], 139) is None
    assert engine_signal([], 1) is None and engine_signal([], 0) is None
    assert verdict([], 137, 500, 1000, signal=engine_signal(srun, 137))[0] == "killed"
    assert verdict([], 139, 500, 1000, signal=engine_signal([], 139))[0] == "failed"


def test_manifest_write_is_atomic(tmp_path):
    m = Manifest(case_id="c", index=0, scene_hash="h", ligwf_version="v", liggghts_version="l")
    write_manifest(tmp_path, m)
    m.reason = object()  # not JSON-serialisable: the write fails half-way
    with pytest.raises(TypeError):
        write_manifest(tmp_path, m)
    assert read_manifest(tmp_path).reason == ""  # the previous manifest is intact
    assert [p.name for p in tmp_path.iterdir()] == ["manifest.json"]  # no temp file left
    assert json.loads((tmp_path / "manifest.json").read_text())["case_id"] == "c"


def test_resume_phase_boundaries():
    # the step counts resume_phase reads
    S = SimpleNamespace(insertion_steps=300, fill=SimpleNamespace(wave_steps=100),
                        numerics=SimpleNamespace(settle_steps=50))
    assert resume_phase(S, 150) == ("fill", 2, True)
    assert resume_phase(S, 200) == ("fill", 3, False)  # wave 3 not inserted yet
    assert resume_phase(S, 300) == ("settle", 0, False)
    assert resume_phase(S, 350) == ("production", 0, False)


def test_resume_mid_fill_keeps_the_top_up_and_its_trim():
    """Fresh and resumed inputs share the fill-wave template: a resume inside the last wave,
    after its insertion, still trims to the exact count; one inside an earlier wave inserts
    the later waves with the top-up margin; every wave ends at the same absolute step."""
    from ligwf.engine.render import TOPUP_MARGIN, render
    from ligwf.engine.resume import RestartFile, render_resume
    from ligwf.scene.workflow import load_workflow

    from helpers import DRUM

    s = load_workflow(DRUM, ["sweep.cg_levels=[3]", "sweep.rules=[weber]"]).cases[0].scaled()
    n, last = s.particles.count, len(s.fill.waves)
    fresh = render(s)["in.liggghts"]
    ends = [f"run {k * s.fill.wave_steps} upto" for k in range(1, last + 1)]
    assert all(e in fresh for e in ends)
    late = list(render_resume(s, RestartFile("r", (last - 1) * s.fill.wave_steps + 5)).values())[0]
    assert f"fix ins{last} " not in late                     # inserted before the restart
    assert f"group ligwf_extra id > {n}" in late and "delete_atoms group ligwf_extra" in late
    assert ends[-1] in late
    early = list(render_resume(s, RestartFile("r", 5)).values())[0]
    assert "fix ins1 " not in early and f"fix ins{last} " in early
    assert f"({n + TOPUP_MARGIN}-count(all))" in early and "delete_atoms group ligwf_extra" in early


def test_a_finished_case_says_finished_in_the_status_tables():
    """The status tables print 'finished' for a done case, also for manifests written when
    its reason was only the step count; other reasons stay as they are."""
    from ligwf.engine.progress import shown_reason

    assert shown_reason("done", "106879 steps") == "finished: all 106879 steps"
    assert shown_reason("done", "finished: all 1000 steps") == "finished: all 1000 steps"
    assert shown_reason("done", "") == "finished"
    assert shown_reason("failed", "engine exit code 1 at step 5 of 10") == \
        "engine exit code 1 at step 5 of 10"


def test_status_table_headers_print_their_units():
    """The units in [ ] reach the terminal (rich read "[s]" as its strike-through tag and
    printed "wall" and "core-s" without them)."""
    import io

    from rich.console import Console

    from ligwf.engine.progress import summary_table

    out = io.StringIO()
    Console(file=out, width=250).print(summary_table([], "cases"))
    text = out.getvalue()
    for head in ("wall [s]", "cores x wall [core-s]", "settle wall [s]", "production wall [s]"):
        assert head in text


def test_steps_between_split_at_the_phase_boundaries():
    # fill 0-300, settle 300-350, production 350-500
    S = SimpleNamespace(insertion_steps=300, numerics=SimpleNamespace(settle_steps=50),
                        total_steps=500)
    assert phase_steps_between(S, 290, 360) == {"fill": 10, "settle": 50, "production": 10}
    assert phase_steps_between(S, 0, 500) == {"fill": 300, "settle": 50, "production": 150}
    assert phase_steps_between(S, 300, 300) == {} and phase_steps_between(S, 400, 350) == {}


def test_a_restart_past_the_killed_attempts_last_row_is_credited_to_it():
    """kill -9 loses the engine's buffered screen: attempt 2's screen ends at step 310 but
    it wrote the restart at 340 that attempt 3 resumes from. The 30 missing steps are its
    (in settling), the per-phase totals stay the sums over the attempts, no step is
    skipped, and a restart the record already reaches changes nothing."""
    from ligwf.engine.attempt import credit_restart
    from ligwf.study.manifest import Attempt

    S = SimpleNamespace(insertion_steps=300, numerics=SimpleNamespace(settle_steps=50),
                        total_steps=500)
    m = Manifest(case_id="c", index=0, scene_hash="h", ligwf_version="", liggghts_version="")
    m.attempts = [Attempt(number=1, started="", steps=120, from_step=0,
                          phases={"fill": {"wall_seconds": 1.0, "steps": 120}}),
                  Attempt(number=2, started="", steps=210, from_step=100,
                          phases={"fill": {"wall_seconds": 2.0, "steps": 200},
                                  "settle": {"wall_seconds": 0.5, "steps": 10}})]
    credit_restart(S, m, 340)
    assert m.attempts[1].steps == 240 and m.attempts[0].steps == 120
    assert m.attempts[1].phases["settle"]["steps"] == 40
    assert m.attempts[1].phases["settle"]["wall_seconds"] == 0.5
    assert sum(p["steps"] for p in m.phases.values()) == sum(a.steps for a in m.attempts)
    assert m.phases["fill"]["steps"] == 320
    credit_restart(S, m, 200)            # already reached: nothing changes
    assert [a.steps for a in m.attempts] == [120, 240]
