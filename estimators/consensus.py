"""Do independent lane detections corroborate each other?

Two detectors that see the same lane independently should differ by no more than their two
measurement noises allow: d = z_a - z_b, S = R_a + R_b, d' S^-1 d below the chi-square
quantile. A detection that agrees with another one is evidence about the road rather than a
fluke of one image, which is what a tracker's gate cannot tell when its own prediction is what
has gone wrong.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.stats import chi2


def corroborated(measurements: Sequence[np.ndarray | None], r: np.ndarray,
                 probability: float = 0.99, points_m: Sequence[float] = (5.0, 15.0)
                 ) -> list[bool]:
    """For each measurement, whether at least one other measurement agrees with it.

    `measurements` are lane polynomials [c0, c1, c2] (None = no detection); `r` is the
    covariance of one detector's coefficients, assumed the same for all and independent
    between detectors. They are compared by the lane's lateral position at `points_m` ahead
    (where a car is steered from: position and heading), not by the far curvature, where two
    fits of the same paint differ most.
    """
    h = np.vander(np.asarray(points_m, dtype=float), 3, increasing=True)
    s = h @ (2.0 * np.asarray(r, dtype=float)) @ h.T
    threshold = float(chi2.ppf(probability, len(points_m)))
    s_inv = np.linalg.inv(s)
    z = [None if m is None else h @ np.asarray(m, dtype=float) for m in measurements]
    agree = [False] * len(z)
    for i, a in enumerate(z):
        for j in range(i + 1, len(z)):
            b = z[j]
            if a is None or b is None:
                continue
            d = a - b
            if float(d @ s_inv @ d) <= threshold:
                agree[i] = agree[j] = True
    return agree
