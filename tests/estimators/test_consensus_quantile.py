"""`corroborated` with its chi-square quantile remembered gives the verdicts of the quantile
computed on every call (the straightforward reference), including for settings that change
between calls."""

import numpy as np
from scipy.stats import chi2

from lanekeep.estimators.consensus import _chi2_quantile, corroborated


def _reference(measurements, r, probability, points_m):
    h = np.vander(np.asarray(points_m, dtype=float), 3, increasing=True)
    threshold = float(chi2.ppf(probability, len(points_m)))
    z = [None if m is None else h @ m for m in measurements]
    agree = [False] * len(z)
    for i in range(len(z)):
        for j in range(i + 1, len(z)):
            if z[i] is None or z[j] is None:
                continue
            d = z[i] - z[j]
            if float(d @ np.linalg.solve(h @ (r + r) @ h.T, d)) <= threshold:
                agree[i] = agree[j] = True
    return agree


def test_the_remembered_quantile_is_scipys():
    for p in (0.9, 0.95, 0.99, 0.999):
        for dof in (1, 2, 3):
            assert _chi2_quantile(p, dof) == float(chi2.ppf(p, dof))
            assert _chi2_quantile(p, dof) == float(chi2.ppf(p, dof))  # remembered: the same


def test_verdicts_match_the_reference_over_random_lanes_and_settings():
    rng = np.random.default_rng(4)
    r = np.diag(np.square([0.05, 0.01, 4e-4]))
    settings = [(0.99, (5.0, 15.0)), (0.9, (5.0, 15.0)), (0.99, (4.0, 10.0, 20.0))]
    borderline = 0
    for k in range(300):
        probability, points = settings[k % len(settings)]
        base = rng.normal(0.0, [0.5, 0.02, 1e-3])
        lanes = [base + rng.normal(0.0, [0.08, 0.012, 5e-4]) for _ in range(3)]
        lanes[rng.integers(3)] = None if k % 7 == 0 else lanes[0]
        got = corroborated(lanes, r, probability, points)
        assert got == _reference(lanes, r, probability, points)
        borderline += any(got) and not all(got)
    assert borderline > 10  # the verdicts split: the threshold decides something
