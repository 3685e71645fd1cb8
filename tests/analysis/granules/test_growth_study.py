"""ligwf.analysis.granules.growth_study: per-seed criteria and the k-of-n verdict on tables whose
answer is known, and the committed README writer on them."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ligwf.analysis.granules.growth_study import Criteria, cadence_table, seed_table, verdict


def _rows(case_id: str, share0: float, growth: float, survival: float, spanning: bool = False,
          wall: float = 0.2, n: int = 40) -> pd.DataFrame:
    t = 0.5 + 0.1 * np.arange(n)
    rng = np.random.default_rng(abs(hash(case_id)) % 2**32)
    return pd.DataFrame({
        "case_id": case_id, "time": t, "revolutions": t,
        "share_2": share0, "share_10": share0 + growth * t + rng.normal(0, 1e-4, n),
        "count_10": 3, "d50_particles": 20.0, "largest": 30, "spanning": spanning,
        "survival": survival, "comove_ratio": 0.3, "wall_share": wall, "bed_wall_share": 0.2,
        "continued": 1, "born": 0, "died": 0, "broke": 0, "coalesced": 0, "accreted": 2,
        "eroded": 1, "dispersed": 0})


def _flows(case_id: str, angle: float) -> pd.DataFrame:
    return pd.DataFrame({"case_id": case_id, "time": np.linspace(0, 5, 20),
                         "angle_of_repose": angle, "rigid_fraction": 0.3})


def _study(n_good: int, n: int = 5) -> tuple[pd.DataFrame, pd.DataFrame]:
    rows, flows = [], []
    for k in range(n):
        wet, twin = f"cg1-none-r{k}", f"cg1-none-r{k}_cohesionless"
        good = k < n_good
        rows.append(_rows(wet, 0.05, 0.01 if good else -0.001, 0.7 if good else 0.2))
        rows.append(_rows(twin, 0.001, 0.0, 0.0))
        flows += [_flows(wet, 40.0), _flows(twin, 39.5 if good else 35.0)]
    return pd.concat(rows, ignore_index=True), pd.concat(flows, ignore_index=True)


def test_every_criterion_per_seed_and_k_of_n():
    rows, flows = _study(n_good=4)
    seeds = seed_table(rows, flows)
    assert list(seeds["seed"]) == [f"cg1-none-r{k}" for k in range(5)]
    assert list(seeds["pass_growth"]) == [True] * 4 + [False]
    assert list(seeds["pass_survival"]) == [True] * 4 + [False]
    assert seeds["pass_control"].all() and seeds["pass_no_spanning"].all()
    assert list(seeds["flow_matched"]) == [True] * 4 + [False]
    ver = verdict(seeds).set_index("criterion")
    assert ver.loc["growth", "seeds_pass"] == 4 and ver.loc["growth", "passes"]
    assert ver.loc["regime", "passes"] and ver.loc["regime", "seeds_pass"] == 4


def test_three_of_five_fails_and_so_does_the_regime():
    seeds = seed_table(*_study(n_good=3))
    ver = verdict(seeds).set_index("criterion")
    assert not ver.loc["survival", "passes"] and ver.loc["survival", "seeds_pass"] == 3
    assert not ver.loc["regime", "passes"]


def test_a_control_with_as_many_granules_fails_the_control_criterion():
    rows, flows = _study(n_good=5)
    twin = rows.case_id.str.endswith("_cohesionless")
    rows.loc[twin, "share_10"] = rows.loc[~twin, "share_10"].to_numpy()
    seeds = seed_table(rows, flows)
    assert not seeds["pass_control"].any()
    assert not verdict(seeds).set_index("criterion").loc["control", "passes"]


def test_no_granules_at_all_is_no_evidence_not_a_pass():
    rows, flows = _study(n_good=5)
    rows["share_10"] = 0.0
    rows["survival"] = np.nan
    seeds = seed_table(rows, flows)
    assert not seeds["pass_control"].any() and not seeds["pass_survival"].any()
    assert not verdict(seeds, Criteria()).set_index("criterion").loc["regime", "passes"]


def test_cadence_table_compares_the_same_start_frames():
    shares = pd.DataFrame({"case_id": "a", "cadence": [0.01, 0.05, 0.01, 0.05, 0.05],
                           "time": [0.5, 0.5, 0.6, 0.6, 0.7],
                           "share_10": [0.1, 0.2, 0.1, 0.2, 0.9]})
    cad = cadence_table(shares).set_index("cadence")["share_10"]
    assert cad[0.01] == 0.1 and cad[0.05] == 0.2      # 0.7 s has one cadence only: left out


def test_the_results_readme_reads_the_verdict_from_the_tables(tmp_path):
    from scripts.granule_growth_results import readme

    seeds = seed_table(*_study(n_good=3))
    ver = verdict(seeds)
    seeds.to_csv(tmp_path / "s.csv", index=False)
    ver.to_csv(tmp_path / "v.csv", index=False)
    cad = pd.DataFrame({"case_id": ["cg1-none-r0"] * 2, "cadence": [0.01, 0.05],
                        "share_10": [0.01, 0.02]})
    cases = pd.DataFrame({"case_id": ["cg1-none-r0"], "particles": [1861],
                          "production_s": [10.0], "frames": [1000], "status": ["done"]})
    text = readme(pd.read_csv(tmp_path / "s.csv"), pd.read_csv(tmp_path / "v.csv"), cad, cases)
    assert "| survival |" in text and "3 of 5 | no |" in text
    assert "The regime does not pass: it fails survival (3 of 5)" in text
    assert "GSD transfer across CG levels stays unvalidated" in text


def test_calibration_rounds_keep_one_wet_reference_then_every_candidate(tmp_path):
    """Two calibrate-control folders: the wet reference both measured counts once (round 1),
    the candidates of both follow in round order."""
    from ligwf.analysis.granules.growth_study import calibration_rounds
    from ligwf.study.layout import CALIBRATION_TABLE

    folders = []
    for k, frictions in enumerate(((0.8, 1.0), (0.65,))):
        folder = tmp_path / f"cal{k + 1}"
        folder.mkdir()
        pd.DataFrame([{"case_id": "wet-r0", "role": "wet reference", "friction": 0.5}]
                     + [{"case_id": f"c{k}{i}", "role": "candidate", "friction": f}
                        for i, f in enumerate(frictions)]).to_csv(folder / CALIBRATION_TABLE,
                                                                  index=False)
        folders.append(folder)
    cal = calibration_rounds(tuple(folders))
    assert list(cal["role"]) == ["wet reference", "candidate", "candidate", "candidate"]
    assert list(cal["round"]) == [1, 1, 1, 2]
    assert list(cal["friction"]) == [0.5, 0.8, 1.0, 0.65]
