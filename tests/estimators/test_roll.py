"""Body roll compensation (estimators/roll.py): the lane moved by the error roll adds, from the
lateral accelerometer; off in the paper's loop and with a zero gradient."""

import math
from dataclasses import replace

import numpy as np
import pytest

from lanekeep.detectors.base import LaneEstimate
from lanekeep.driver.paper_mode import roll_compensation
from lanekeep.estimators.roll import RollCompensation, RollFilter, corrected
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.loop.paper_mode import with_mode
from lanekeep.scenario.schema import InvalidValue, load_scenario


def _estimate(offset_m: float) -> LaneEstimate:
    left, right = np.array([1.85 - offset_m, 0.01, 1e-3]), np.array([-1.85 - offset_m, 0.01, 1e-3])
    x = 4.0
    centre_at_x = (LanePoly.of(left).y(x) + LanePoly.of(right).y(x)) / 2
    return LaneEstimate(True, offset_m=-centre_at_x, x_m=x, left=left, right=right,
                        confidence=0.9)


def test_the_offset_and_the_lane_move_together():
    e = _estimate(0.2)
    fixed = corrected(e, 0.03)
    assert fixed.offset_m == pytest.approx(e.offset_m - 0.03, abs=1e-12)
    assert fixed.offset_m == pytest.approx(LanePoly.of(fixed.center).offset_m(fixed.x_m), abs=1e-12)
    np.testing.assert_allclose(fixed.left[1:], e.left[1:])  # heading and curvature kept
    invalid = LaneEstimate.invalid("nothing")
    assert corrected(invalid, 0.03) is invalid


def test_the_error_is_the_roll_from_the_accelerometer_times_the_camera_lever():
    roll = RollCompensation(0.62, (("front", 2.4), ("rear", 2.5)))
    assert roll.offset_error_m("front", 2.0) == pytest.approx(2.4 * math.radians(1.24))
    assert roll.offset_error_m("rear", -1.0) == pytest.approx(-2.5 * math.radians(0.62))
    assert roll.offset_error_m("front", float("nan")) == 0.0
    assert RollCompensation().offset_error_m("front", 3.0) == 0.0


def test_default_loop_compensates_and_the_papers_does_not():
    ours = load_scenario("clear_curve")
    assert roll_compensation(ours.estimation).offset_error_m("front", 1.0) > 0.0
    paper = with_mode(ours, "paper")
    assert roll_compensation(paper.estimation).offset_error_m("front", 1.0) == 0.0
    off = replace(ours.estimation, roll_gradient_deg_per_mps2=0.0)
    assert roll_compensation(off).offset_error_m("rear", 1.0) == 0.0
    with pytest.raises(InvalidValue, match="roll_gradient"):
        replace(ours.estimation, roll_gradient_deg_per_mps2=-1.0)


def test_the_filter_follows_a_steady_turn_and_shrugs_off_a_spike():
    comp = RollCompensation(0.62, (("front", 2.4),), filter_s=0.3)
    steady = RollFilter(comp, 0.1)
    for _ in range(30):
        steady.update(1.5)
    assert steady.accel_lat_mps2 == pytest.approx(1.5, rel=1e-3)
    spiked = RollFilter(comp, 0.1)
    spiked.update(8.5)  # a kerb: clipped to 6 m/s^2, then a third of it passes in one step
    assert spiked.accel_lat_mps2 == pytest.approx(6.0 * (1 - math.exp(-1 / 3)))
    spiked.update(float("nan"))
    assert math.isfinite(spiked.accel_lat_mps2)
