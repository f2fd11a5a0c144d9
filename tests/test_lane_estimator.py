"""The closed loop's estimator behind one call: centring, tracking, choice, timing laps."""

from __future__ import annotations

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.estimators.lane_estimator import EgoMotion, EstimatorSettings, LaneEstimator

WIDTH = 3.7
NAMES = ["hough", "sliding_window"]


def _lane(c0: float, heading: float = 0.0) -> LaneEstimate:
    """A detection of a straight lane whose centre is at y = c0 (both boundaries)."""
    left = np.array([c0 + WIDTH / 2, heading, 0.0])
    right = np.array([c0 - WIDTH / 2, heading, 0.0])
    return LaneEstimate(valid=True, offset_m=-c0, x_m=4.0, left=left, right=right)


def _ego(k: int, speed: float = 15.0) -> EgoMotion:
    return EgoMotion(0.1, speed, 0.0, 0.0, (speed * 0.1 * k, 0.0, 0.0), speed * 0.1 * (k + 1))


def _estimator() -> LaneEstimator:
    return LaneEstimator(NAMES, EstimatorSettings(lane_width_prior_m=WIDTH), reference_x_m=-4.0)


def test_one_boundary_is_centred_with_the_lane_width():
    estimator = _estimator()
    left_only = LaneEstimate(valid=True, x_m=4.0, left=np.array([1.85, 0.0, 0.0]))
    np.testing.assert_allclose(estimator.centre_of(left_only), [0.0, 0.0, 0.0])
    assert estimator.centre_of(LaneEstimate.invalid("none")) is None


def test_one_boundary_uses_the_lane_width_the_detections_measured():
    """The estimator never reads the road's width: two-boundary detections of a 3.3 m lane
    move its running width from the 3.7 m prior towards 3.3 m, and a one-boundary detection
    is then centred with it; implausible widths are ignored."""
    estimator = _estimator()
    narrow = LaneEstimate(valid=True, offset_m=0.0, x_m=4.0, left=np.array([1.65, 0.0, 0.0]),
                          right=np.array([-1.65, 0.0, 0.0]))
    wide = LaneEstimate(valid=True, offset_m=0.0, x_m=4.0, left=np.array([4.0, 0.0, 0.0]),
                        right=np.array([-4.0, 0.0, 0.0]))
    for k in range(100):
        estimator.update({"hough": narrow, "sliding_window": wide}, narrow, _ego(k))
    assert abs(estimator.lane_width_m - 3.3) < 0.01
    left_only = LaneEstimate(valid=True, x_m=4.0, left=np.array([1.65, 0.0, 0.0]))
    assert abs(estimator.centre_of(left_only)[0]) < 0.01
    estimator.reset()
    assert estimator.lane_width_m == WIDTH


def test_a_steady_lane_is_tracked_and_handed_on_with_its_offset():
    estimator = _estimator()
    laps: list[str] = []
    for k in range(20):
        out = estimator.update({n: _lane(0.2) for n in NAMES}, _lane(0.2), _ego(k),
                               lap=laps.append)
    assert set(out.tracked) == set(NAMES)
    assert out.tracker_status == {n: "updated" for n in NAMES}
    np.testing.assert_allclose(out.centre[0], 0.2, atol=1e-4)  # converged within 0.1 mm
    assert abs(out.offset_m - (-0.2)) < 1e-4
    assert out.selected in (0, 1)
    assert laps == ["track", "mmae"] * 20


def test_output_leaves_a_model_whose_detector_has_nothing_for_one_that_was_updated():
    estimator = _estimator()
    for k in range(10):
        out = estimator.update({n: _lane(0.0) for n in NAMES}, _lane(0.0), _ego(k))
    favourite = out.selected
    other = 1 - favourite
    detections = {NAMES[favourite]: LaneEstimate.invalid("lost"), NAMES[other]: _lane(0.05)}
    out = estimator.update(detections, _lane(0.0), _ego(10))
    assert out.tracker_status[NAMES[favourite]] == "missed"
    assert out.selected == other
    np.testing.assert_allclose(out.centre, out.tracked[NAMES[other]])


def test_reset_forgets_the_tracks():
    estimator = _estimator()
    estimator.update({n: _lane(0.3) for n in NAMES}, _lane(0.3), _ego(0))
    estimator.reset()
    out = estimator.update({n: LaneEstimate.invalid("none") for n in NAMES},
                           LaneEstimate.invalid("none"), _ego(1))
    assert out.centre is None and out.offset_m is None
    assert all(c is None for c in out.tracked.values())


def test_the_tracker_tuning_file_is_read_strictly():
    import tomllib
    from importlib import resources

    import pytest

    from lanekeep.config_io import ConfigError
    from lanekeep.estimators.lane_estimator import TRACKER_TOML, closed_loop_tracker

    text = resources.files("lanekeep.estimators").joinpath(TRACKER_TOML).read_text()
    config = closed_loop_tracker(text)
    assert config.coast_with_rates is False
    data = tomllib.loads(text)
    measured = np.asarray(data["measured_coefficient_covariance"])
    np.testing.assert_allclose(config.coefficient_r, data["r_scale"] * measured)
    with pytest.raises(ConfigError, match="tracker.c1_accel_psd"):
        closed_loop_tracker(text.replace("c1_accel_psd_ps3 =", "c1_accel_psd =", 1))
    with pytest.raises(ConfigError, match="r_scale"):
        closed_loop_tracker(text.replace("r_scale = 4.0", ""))
    with pytest.raises(ConfigError, match="gate_probability"):
        closed_loop_tracker(text + "gate_probability = 1.5\n")


def test_paper_settings_hand_on_the_selected_detection_at_its_own_row():
    """Paper mode's PID input is the selected model's detection as the detector reported it
    (offset and look-ahead), even when its track's gate rejects it; the MMAE compares every
    offset at the car (x = 0), the reference's too."""
    from lanekeep.paper_mode import estimator_settings
    from lanekeep.scenario import EstimationConfig

    settings = estimator_settings(EstimationConfig(mode="paper"))
    assert (settings.residual_mode, settings.model_lane, settings.output_at) == (
        "one_step_delay", "detection", "nearest_row")
    estimator = LaneEstimator(NAMES, settings, reference_x_m=-4.0)
    for k in range(10):
        estimator.update({n: _lane(0.0) for n in NAMES}, _lane(0.0), _ego(k))
    jump = LaneEstimate(valid=True, offset_m=-1.5, x_m=5.0, left=np.array([3.35, 0.0, 0.0]),
                        right=np.array([-0.35, 0.0, 0.0]))
    out = estimator.update({"hough": jump, "sliding_window": _lane(0.0)}, _lane(0.0), _ego(10))
    assert out.tracker_status == {"hough": "gated", "sliding_window": "updated"}
    assert out.selected == 0  # the argmax (equal so far: the first), not the accepted one
    assert (out.offset_m, out.offset_x_m) == (-1.5, 5.0)
    assert out.reference_x_m == 0.0
