"""A lane line as the polynomial y(x) = c0 + c1 x + c2 x^2 in the vehicle ground frame (x forward,
y left, metres, origin on the ground under the middle of the wheelbase).

Detectors, trackers, the controller, the scorer and the overlays all read lane polynomials; they
read them here, so that each computes the same bits for the same line: y(x) is
c0 + c1 x + c2 (x x), summed left to right, the car's offset from the line is -y(x). Coefficient
arrays are ordered low order first, [c0, c1, c2], as `LaneEstimate` and the trackers hold them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LanePoly:
    """y(x) = c0 + c1 x + c2 x^2 (metres); `x` may be a number or an array.

    The coefficients are held as numpy float64: with a float32 `x` a Python float would let
    NumPy compute in float32 (NEP 50), a float64 coefficient keeps the sum in float64.
    """

    c0: float  # m, y at x = 0
    c1: float  # dy/dx at x = 0
    c2: float  # 1/m, half of d2y/dx2

    def __post_init__(self) -> None:
        for name in ("c0", "c1", "c2"):
            object.__setattr__(self, name, np.float64(getattr(self, name)))

    @classmethod
    def of(cls, coeffs) -> LanePoly:
        """From an array-like [c0, c1, c2] (low order first), as estimates and trackers hold."""
        c = np.asarray(coeffs, dtype=float)
        if c.shape != (3,):
            raise ValueError(f"a lane polynomial has 3 coefficients [c0, c1, c2], got {c.shape}")
        return cls(c[0], c[1], c[2])

    @property
    def coeffs(self) -> np.ndarray:
        """[c0, c1, c2] as a new float64 array."""
        return np.array([self.c0, self.c1, self.c2])

    def y(self, x):
        """Lateral position (m, + = left) of the line at `x`."""
        return self.c0 + self.c1 * x + self.c2 * np.square(x)

    def offset_m(self, x):
        """The car's lateral offset from the line at `x`, + = car left of it: the offset
        convention of `LaneEstimate.offset_m` (the line lies at y = -offset)."""
        return -self.y(x)

    def slope(self, x):
        """dy/dx at `x`: the tangent of the line's heading relative to the car's."""
        return self.c1 + 2.0 * self.c2 * x

    def heading_rad(self, x: float) -> float:
        """Heading of the line at `x` relative to the car's (rad, + = turning left)."""
        return math.atan(self.slope(x))

    def curvature_1pm(self, x):
        """Signed curvature at `x` (1/m, + = bending left): 2 c2 / (1 + y'^2)^1.5, not 2 c2
        alone, which a quadratic fitted over a tight arc overstates."""
        slope = self.slope(x)
        return 2.0 * self.c2 / (1.0 + slope * slope) ** 1.5
