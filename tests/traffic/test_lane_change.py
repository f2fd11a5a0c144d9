"""The minimum-jerk lateral path of a lane change (lanekeep/traffic/lane_change.py)."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.traffic.lane_change import PEAK_SPEED_FACTOR, lateral_offset, lateral_speed


def test_ends_and_middle():
    assert lateral_offset(-1.75, 1.75, 4.0, 0.0) == -1.75
    assert lateral_offset(-1.75, 1.75, 4.0, 4.0) == pytest.approx(1.75, abs=1e-12)
    # τ = 1/2: 10/8 - 15/16 + 6/32 = 0.5 of the way
    assert lateral_offset(-1.75, 1.75, 4.0, 2.0) == pytest.approx(0.0, abs=1e-12)
    # τ = 1/4: 10/64 - 15/256 + 6/1024 = 0.103515625
    assert lateral_offset(0.0, 3.5, 4.0, 1.0) == pytest.approx(3.5 * 0.103515625, abs=1e-12)


def test_clamped_outside_the_change():
    assert lateral_offset(0.0, 3.5, 4.0, -1.0) == 0.0
    assert lateral_offset(0.0, 3.5, 4.0, 9.0) == 3.5
    assert lateral_speed(0.0, 3.5, 4.0, -1.0) == 0.0 == lateral_speed(0.0, 3.5, 4.0, 9.0)


def test_rest_to_rest_and_peak_speed():
    t = np.linspace(0.0, 3.0, 3001)
    speeds = np.array([lateral_speed(1.75, -1.75, 3.0, ti) for ti in t])
    assert speeds[0] == 0.0 and speeds[-1] == pytest.approx(0.0, abs=1e-12)
    # peak |dr/dt| = 1.875 * 3.5 / 3.0 = 2.1875 m/s at mid-change, towards r1
    assert PEAK_SPEED_FACTOR == 1.875
    assert speeds.min() == pytest.approx(-2.1875, abs=1e-9)
    assert t[speeds.argmin()] == pytest.approx(1.5, abs=1e-9)


def test_speed_is_the_derivative_of_the_offset():
    h = 1e-6
    for ti in (0.3, 1.1, 2.0, 3.7):
        numeric = (lateral_offset(0.0, 3.5, 4.0, ti + h)
                   - lateral_offset(0.0, 3.5, 4.0, ti - h)) / (2 * h)
        assert lateral_speed(0.0, 3.5, 4.0, ti) == pytest.approx(numeric, abs=1e-6)


def test_a_change_needs_a_duration():
    with pytest.raises(ValueError, match="duration"):
        lateral_offset(0.0, 3.5, 0.0, 1.0)
