"""A detection's confidence band scales its R: the bands, the tuning file, the tracker and the
estimator."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.detectors.base import LaneEstimate
from lanekeep.estimators.confidence import ConfidenceBands
from lanekeep.estimators.kalman import LaneTracker, TrackerConfig, UpdateStatus
from lanekeep.estimators.lane_estimator import (
    TRACKER_TOML,
    EgoMotion,
    EstimatorSettings,
    LaneEstimator,
    closed_loop_tracker,
)

WIDTH = 3.7


def _lane(c0: float, confidence: float) -> LaneEstimate:
    left = np.array([c0 + WIDTH / 2, 0.0, 0.0])
    right = np.array([c0 - WIDTH / 2, 0.0, 0.0])
    return LaneEstimate(valid=True, offset_m=-c0, x_m=4.0, left=left, right=right,
                        confidence=confidence)


def _ego(k: int, speed: float = 15.0) -> EgoMotion:
    return EgoMotion(0.1, speed, 0.0, 0.0, (speed * 0.1 * k, 0.0, 0.0), speed * 0.1 * (k + 1))


def test_a_confidence_falls_in_the_band_its_edges_give():
    bands = ConfidenceBands((0.3, 0.6), (4.0, 1.0, 0.5))
    assert [bands.band(c) for c in (0.0, 0.29, 0.3, 0.59, 0.6, 1.0)] == [0, 0, 1, 1, 2, 2]
    assert bands.scale(0.1) == 4.0 and bands.scale(0.9) == 0.5


@pytest.mark.parametrize("edges, scales", [((0.3, 0.6), (1.0, 2.0)),  # one scale short
                                           ((0.6, 0.3), (1.0, 2.0, 3.0)),  # edges descend
                                           ((0.3,), (1.0, 0.0)),  # a zero factor
                                           ((0.3,), (1.0, float("nan")))])
def test_bands_that_cannot_be_meant_are_refused(edges, scales):
    with pytest.raises(ValueError):
        ConfidenceBands(edges, scales)


def test_the_shipped_tuning_file_gives_the_classical_detectors_their_bands():
    from importlib import resources

    from lanekeep.core.config_io import ConfigError

    text = resources.files("lanekeep.estimators").joinpath(TRACKER_TOML).read_text()
    tuning = closed_loop_tracker(text)
    for name in ("hough", "sliding_window", "lanenet"):
        bands = tuning.bands_for(name)
        assert bands is not None and len(bands.scales) == len(bands.edges) + 1
        # measured: the least confident detections are the noisiest
        assert bands.scales[0] > 1.0 > bands.scales[-1]
    assert tuning.bands_for("my_plugin:Detector") is None
    with pytest.raises(ConfigError, match="confidence_noise_by_detector.hough"):
        closed_loop_tracker(text.replace("\nhough = { edges = [", "\nhough = { edges = [2.0, ",
                                         1))
    with pytest.raises(ConfigError, match="confidence_noise_by_detector.hough"):
        closed_loop_tracker(text.replace("\nhough = { edges", "\nhough = { bins", 1))


def test_a_larger_r_scale_moves_the_track_less_and_widens_its_gate():
    def tracker_after(step: float, r_scale: float) -> tuple[LaneTracker, object]:
        tracker = LaneTracker(TrackerConfig())
        for _ in range(20):
            tracker.predict(0.1, 15.0)
            tracker.update_coefficients([0.0, 0.0, 0.0])
        tracker.predict(0.1, 15.0)
        return tracker, tracker.update_coefficients([step, 0.0, 0.0], r_scale)

    sure, _ = tracker_after(0.05, 0.5)
    unsure, _ = tracker_after(0.05, 4.0)
    assert sure.coefficients[0] > unsure.coefficients[0] > 0.0
    _, gated = tracker_after(0.6, 1.0)
    _, taken = tracker_after(0.6, 100.0)
    assert gated.status is UpdateStatus.GATED and taken.status is UpdateStatus.UPDATED
    with pytest.raises(ValueError, match="r_scale"):
        tracker_after(0.05, 0.0)


def test_with_confidence_noise_a_sure_detection_pulls_its_track_harder():
    """Two models see the same steady lane, then the same 10 cm step; the one whose step
    comes with its top confidence band follows further than the one with its lowest band.
    Without the setting both follow alike."""

    def moved(confidence_noise: bool) -> dict[str, float]:
        settings = EstimatorSettings(lane_width_prior_m=WIDTH,
                                     confidence_noise=confidence_noise)
        estimator = LaneEstimator(["hough", "hough_too"], settings, -4.0,
                                  families={"hough_too": "hough"})
        for k in range(30):
            estimator.update({"hough": _lane(0.0, 0.9), "hough_too": _lane(0.0, 0.9)},
                             _lane(0.0, 1.0), _ego(k))
        out = estimator.update({"hough": _lane(0.1, 1.0), "hough_too": _lane(0.1, 0.05)},
                               _lane(0.0, 1.0), _ego(30))
        return {"sure": out.tracked["hough"][0], "unsure": out.tracked["hough_too"][0]}

    on, off = moved(True), moved(False)
    assert on["sure"] > on["unsure"] > 0.0
    assert off["sure"] == pytest.approx(off["unsure"])


def test_confidence_noise_is_a_setting_paper_mode_leaves_out():
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig

    on = EstimationConfig(confidence_noise=True)
    assert estimator_settings(on).confidence_noise is True
    assert estimator_settings(EstimationConfig(mode="paper", confidence_noise=True)
                              ).confidence_noise is False
    kept = EstimationConfig(mode="paper", confidence_noise=True,
                            paper_keeps=("confidence_noise",))
    assert estimator_settings(kept).confidence_noise is True
