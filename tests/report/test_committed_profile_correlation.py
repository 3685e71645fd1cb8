"""docs/results/profile_correlation: the README is what its table gives (the script's
--check), and the estimator tells shared from independent bin errors (its null)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "profile_correlation"
sys.path.insert(0, str(ROOT / "scripts"))
import profile_correlation as pc  # noqa: E402


def test_readme_is_its_table():
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "profile_correlation.py"),
                        "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_measured_bins_are_below_their_null():
    t = pd.read_csv(HERE / pc.CORRELATION)
    assert len(t) == 2 and (t.effective_bins < t.null_effective_bins_low).all()
    assert (t.mean_corr_lag1 > 0.8).all() and (t.null_mean_corr_lag1.abs() < 0.05).all()


def test_a_shared_shift_is_one_bin_and_independent_bins_match_the_null():
    rng = np.random.default_rng(3)
    sizes = [3, 3, 3]
    shared = np.vstack([np.outer(s - s.mean(), np.ones(15))
                        for s in (rng.standard_normal(n) for n in sizes)])
    shared += 1e-6 * rng.standard_normal(shared.shape)
    assert pc.effective_bins(shared, 6)[1] < 1.01
    med, low, _ = pc.null_effective_bins(sizes, 15, trials=300)
    rows = []
    for n in sizes:
        a = rng.standard_normal((n, 15))
        rows.append(a - a.mean(axis=0))
    assert pc.effective_bins(np.vstack(rows), 6)[1] > low
