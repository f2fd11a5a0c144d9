"""Do independent lane detections corroborate each other?

Two detectors that see the same lane independently should differ by no more than their two
measurement noises allow: d = z_a - z_b, S = R_a + R_b, d' S^-1 d below the chi-square
quantile. A detection that agrees with another one is evidence about the road rather than a
fluke of one image, which is what a tracker's gate cannot tell when its own prediction is what
has gone wrong.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
from scipy.stats import chi2


def corroborated(measurements: Sequence[np.ndarray | None],
                 r: np.ndarray | Sequence[np.ndarray], probability: float = 0.99,
                 points_m: Sequence[float] = (5.0, 15.0)) -> list[bool]:
    """For each measurement, whether at least one other measurement agrees with it.

    `measurements` are lane polynomials [c0, c1, c2] (None = no detection); `r` is the
    covariance of a detector's coefficients: one 3x3 matrix for all, or one per measurement
    (detectors differ), the detectors independent of each other. They are compared by the
    lane's lateral position at `points_m` ahead (where a car is steered from: position and
    heading), not by the far curvature, where two fits of the same paint differ most.
    """
    h = np.vander(np.asarray(points_m, dtype=float), 3, increasing=True)
    r = np.asarray(r, dtype=float)
    per_measurement = r if r.ndim == 3 else np.broadcast_to(r, (len(measurements), 3, 3))
    if per_measurement.shape != (len(measurements), 3, 3):
        raise ValueError(f"expected one 3x3 R or one per measurement, got shape {r.shape}")
    threshold = _chi2_quantile(probability, len(points_m))
    z = [None if m is None else h @ np.asarray(m, dtype=float) for m in measurements]
    agree = [False] * len(z)
    for i, a in enumerate(z):
        for j in range(i + 1, len(z)):
            b = z[j]
            if a is None or b is None:
                continue
            d = a - b
            s = h @ (per_measurement[i] + per_measurement[j]) @ h.T  # S = H (R_a + R_b) H'
            if float(d @ np.linalg.solve(s, d)) <= threshold:
                agree[i] = agree[j] = True
    return agree


@functools.lru_cache(maxsize=16)
def _chi2_quantile(probability: float, dof: int) -> float:
    """`chi2.ppf(probability, dof)`, remembered: the gate's probability and number of points
    are settings, and scipy's quantile costs more than the rest of a step's consensus."""
    return float(chi2.ppf(probability, dof))
