"""LanePoly: values of a known parabola, derivatives against finite differences, curvature
against a circle, the offset convention, float64 kept for float32 input, and the exact
arithmetic the detectors, trackers and scorer were built on (golden runs depend on its bits)."""

import math

import numpy as np
import pytest

from lanekeep.geometry.lane_poly import LanePoly


def test_a_known_parabola_at_numbers_and_arrays():
    lane = LanePoly(1.5, -0.1, 0.02)
    assert lane.y(0.0) == 1.5
    assert lane.y(10.0) == pytest.approx(1.5 - 1.0 + 2.0)
    xs = np.array([-10.0, 0.0, 10.0])
    np.testing.assert_allclose(lane.y(xs), [1.5 + 1.0 + 2.0, 1.5, 2.5])
    assert np.shape(lane.y(xs)) == (3,)


def test_the_sum_is_c0_plus_c1_x_plus_c2_times_x_squared_to_the_bit():
    """The order of the float operations is part of the contract: changing it moves the last
    bit of every offset and the golden runs (tools/golden.py) with it."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        c = rng.normal(0.0, [1.0, 0.05, 2e-3])
        x = rng.uniform(-20.0, 40.0, 16)
        lane = LanePoly.of(c)
        assert np.array_equal(lane.y(x), c[0] + c[1] * x + c[2] * (x * x))
        assert np.array_equal(lane.slope(x), c[1] + 2.0 * c[2] * x)


def test_the_offset_is_minus_y():
    lane = LanePoly.of([0.3, 0.01, 1e-3])
    assert lane.offset_m(4.0) == -lane.y(4.0)
    assert LanePoly(0.0, 0.0, 0.0).offset_m(5.0) == 0.0


def test_slope_and_heading_match_finite_differences():
    lane = LanePoly(0.2, 0.05, -3e-3)
    h = 1e-5
    for x in (-12.0, 0.0, 7.5):
        numeric = (lane.y(x + h) - lane.y(x - h)) / (2 * h)
        assert lane.slope(x) == pytest.approx(numeric, rel=1e-7)
        assert lane.heading_rad(x) == pytest.approx(math.atan(numeric), rel=1e-7)


def test_curvature_of_a_parabola_osculating_a_circle():
    """y = x^2 / (2 R) touches a circle of radius R at x = 0, bending left (+)."""
    radius = 250.0
    lane = LanePoly(0.0, 0.0, 1.0 / (2.0 * radius))
    assert lane.curvature_1pm(0.0) == pytest.approx(1.0 / radius)
    assert LanePoly(0.0, 0.0, -1.0 / (2.0 * radius)).curvature_1pm(0.0) == pytest.approx(
        -1.0 / radius)
    assert abs(lane.curvature_1pm(30.0)) < abs(lane.curvature_1pm(0.0))  # flattens where steep


def test_float32_input_is_computed_in_float64():
    lane = LanePoly.of(np.array([1.0, 0.1, 1e-3], dtype=np.float32))
    x = np.linspace(4.0, 30.0, 5, dtype=np.float32)
    assert lane.y(x).dtype == np.float64
    assert lane.c1 == np.float64(np.float32(0.1))


def test_of_takes_three_coefficients_and_round_trips():
    c = np.array([0.5, -0.02, 4e-4])
    lane = LanePoly.of(c)
    assert np.array_equal(lane.coeffs, c)
    assert lane == LanePoly(0.5, -0.02, 4e-4)
    assert hash(lane) == hash(LanePoly(0.5, -0.02, 4e-4))
    with pytest.raises(ValueError, match="3 coefficients"):
        LanePoly.of([1.0, 2.0])
    with pytest.raises(ValueError, match="3 coefficients"):
        LanePoly.of(np.zeros((3, 2)))


def test_it_is_frozen():
    lane = LanePoly(0.0, 0.0, 0.0)
    with pytest.raises(AttributeError):
        lane.c0 = 1.0  # type: ignore[misc]
