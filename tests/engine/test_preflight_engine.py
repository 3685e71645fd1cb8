"""Pre-flight verdicts the engine bears out (issue 21): stiff particles near 0.2 of the
Rayleigh time, and a bed too cohesive to flow."""

from __future__ import annotations

import subprocess
import sys

import pytest

from ligwf.scene.stability import MARGINAL, OK, REFUSED, UnstableCase, preflight
from ligwf.scene.workflow import load_workflow
from ligwf.pipeline.prepare import prepare

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
#: the stiff closed drum of issue 21: 320 CG2 particles, E = 5e9 Pa (hard_particles)
STIFF = ["sweep.rules=[weber]", "sweep.cg_levels=[2]", "scene.drum.periodic=false",
         "scene.process.particle_count=2560", "scene.particles.youngs_modulus=5.0e+9"]


def findings(overrides: list[str], allow: bool = True) -> dict:
    prepared = prepare(load_workflow(WORKFLOW, overrides), (), allow)
    (rc,) = prepared.rendered[:1]
    return {f.check: f for f in preflight(rc.scaled, rc.case.case_id).findings}


def test_stiff_particles_at_019_of_rayleigh_are_refused_and_016_runs():
    with pytest.raises(UnstableCase, match=r"0.19x the Rayleigh time.*limit 0.18x.*hard"):
        prepare(load_workflow(WORKFLOW, STIFF + ["scene.numerics.dt_rayleigh_fraction=0.19"]))
    ok = findings(STIFF + ["scene.numerics.dt_rayleigh_fraction=0.16"], allow=False)
    assert ok["dt_rayleigh"].verdict == OK
    # soft particles keep the documented 0.2: 0.19 is marginal, and the suggestion is one
    # the case does not already meet
    soft = findings(["sweep.rules=[weber]", "scene.numerics.dt_rayleigh_fraction=0.19"])
    assert soft["dt_rayleigh"].verdict == MARGINAL
    assert "dt_rayleigh_fraction <= 0.18" in soft["dt_rayleigh"].message


def test_a_bed_held_by_its_bridges_is_warned_that_it_will_not_flow():
    wet = findings(["sweep.rules=[weber]", "scene.liquid.surface_tension=0.3"])
    assert wet["bed_flow"].verdict == MARGINAL and wet["bed_flow"].value > 1.0
    assert "will not flow" in wet["bed_flow"].message
    plain = findings(["sweep.rules=[weber]"])
    assert plain["bed_flow"].verdict == OK and plain["bed_flow"].value < 0.3
    dry = findings(["sweep.rules=[none]", "scene.liquid.model=none",
                    "scene.analysis.contact_dumps=false"])
    assert "bed_flow" not in dry
    assert REFUSED not in {f.verdict for f in wet.values()}


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.slow
def test_the_bed_the_preflight_says_will_not_flow_turns_as_a_block(tmp_path):
    """The two beds side by side (planned ensemble). After the spin-up (the first 0.3 s of
    production, in which any bed at rest turns with the drum up to its angle of repose),
    the bed warned turns with the drum rigidly (>= 95 % of its particles at the wall's
    rotation) in several frames and has frames without a free surface (it breaks off as
    a block); the other never turns rigidly and always has an angle of repose. (Measured:
    the warned bed climbs to 66 deg as one block, breaks, and turns rigidly again in the
    last 5 of 10 frames; the other stays at <= 0.85 rigid, 20-62 deg.)"""
    from ligwf.analysis.frames.dumps import read_particles
    from ligwf.analysis.flow.frame import DrumGeometry, frame_flow
    from ligwf.study.study import Study

    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW),
                        "--out", str(out), "--cores", "2", "--set", "sweep.rules=[weber]",
                        "--set", "sweep.scene.liquid.surface_tension=[0.024, 1.0]",
                        "--set", "scene.process.settle_time=0.2",
                        "--set", "scene.process.run_time=0.8"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    warned = {line.split(":")[2].strip() for line in r.stderr.splitlines()
              if "will not flow" in line}
    shares, angles = {}, {}
    for case in Study.open(out).cases:
        s = case.scaled
        d_mean = sum(d * f for d, f in zip(s.particles.diameters, s.particles.number_fractions))
        geo = DrumGeometry(radius=0.5 * s.drum.diameter, axis=s.drum.axis, omega=s.drum.omega,
                           d_mean=d_mean)
        spun_up = case.production_start_step + round(0.3 / s.numerics.dt)
        flows = [frame_flow(read_particles(case.path / "post" / f"particles_{step}.vtu"), geo)
                 for step in case.expected_dump_steps(s.total_steps) if step >= spun_up]
        assert len(flows) >= 8
        shares[case.case_id] = [f.rigid_fraction for f in flows]
        angles[case.case_id] = [f.angle_of_repose for f in flows]
    assert len(warned) == 1 and warned <= set(shares), (warned, r.stderr)
    for case_id, share in shares.items():
        rigid = sum(x >= 0.95 for x in share)
        no_angle = sum(a != a for a in angles[case_id])      # nan: no free surface
        if case_id in warned:
            assert rigid >= 4 and no_angle >= 1, (case_id, share, angles[case_id])
        else:
            assert rigid == 0 and no_angle == 0, (case_id, share, angles[case_id])
