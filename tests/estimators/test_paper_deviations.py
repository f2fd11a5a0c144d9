"""Paper mode to the letter, each of our deviations a named option (`[estimation] paper_keeps`):
paper mode takes the paper's choice for every one, a named one keeps ours, and each choice does
what it says in the estimator (eq. 8's covariance, the floor, a missing model's value)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.config import load_config
from lanekeep.driver.paper_mode import (
    ESTIMATOR_CHOICES,
    FINITE_FLOOR,
    estimator_settings,
    front_detector_config,
    roll_compensation,
)
from lanekeep.estimators.lane_estimator import PAPER_R_M2, EgoMotion, LaneEstimator
from lanekeep.scenario.estimation import PAPER_DEVIATIONS, EstimationConfig

WIDTH = 3.7
NAMES = ["hough", "sliding_window"]


def _lane(c0: float) -> LaneEstimate:
    return LaneEstimate(valid=True, offset_m=-c0, x_m=4.0,
                        left=np.array([c0 + WIDTH / 2, 0.0, 0.0]),
                        right=np.array([c0 - WIDTH / 2, 0.0, 0.0]))


def _ego(k: int) -> EgoMotion:
    return EgoMotion(0.1, 15.0, 0.0, 0.0, (1.5 * k, 0.0, 0.0), 1.5 * (k + 1))


def test_paper_mode_takes_the_papers_choice_for_every_deviation_and_a_kept_one_stays_ours():
    assert set(ESTIMATOR_CHOICES) <= set(PAPER_DEVIATIONS)
    ours = EstimationConfig().estimator_settings()
    paper = estimator_settings(EstimationConfig(mode="paper"))
    assert (paper.residual_covariance, paper.probability_floor, paper.missing_model) == (
        "paper", FINITE_FLOOR, "hold")
    for deviation, choices in ESTIMATOR_CHOICES.items():
        for key, value in choices.items():
            assert getattr(paper, key) == value
        kept = estimator_settings(EstimationConfig(mode="paper", paper_keeps=(deviation,)))
        for key in choices:
            assert getattr(kept, key) == getattr(ours, key), (deviation, key)
        others = {k for d, c in ESTIMATOR_CHOICES.items() if d != deviation for k in c}
        for key in others - set(choices):
            assert getattr(kept, key) == getattr(paper, key), (deviation, key)
    # outside paper mode the list changes nothing
    assert estimator_settings(EstimationConfig(paper_keeps=tuple(PAPER_DEVIATIONS))) == ours


def test_an_unknown_deviation_is_named():
    with pytest.raises(InvalidValue, match="unknown deviation 'floor'"):
        EstimationConfig(mode="paper", paper_keeps=("floor",))


def test_roll_windows_and_binarisation_are_deviations_too():
    paper = EstimationConfig(mode="paper")
    assert roll_compensation(paper).offset_error_m("front", 1.0) == 0.0
    kept = EstimationConfig(mode="paper", paper_keeps=("roll_compensation",))
    assert roll_compensation(kept).offset_error_m("front", 1.0) > 0.0
    config = front_detector_config("hough", "paper")
    assert config.hough.binarisation == config.sliding_window.binarisation == "paper"
    pre = config.preprocess
    assert (pre.vehicle_dark_ratio, pre.streak_min_rows, pre.min_coherence, pre.max_fill,
            pre.min_blob_length_m) == (0.0, 0, 0.0, 1.0, 0.0)
    ours = front_detector_config("hough", "paper", keeps=("binarisation",))
    assert ours.hough.binarisation == "image" and ours.preprocess.min_coherence > 0.0
    flecks = load_config()
    flecks = replace(flecks, preprocess=replace(flecks.preprocess, min_blob_length_m=1.0,
                                                join_along_m=1.5))
    paper_pre = front_detector_config("hough", "paper", flecks).preprocess
    assert paper_pre.min_blob_length_m == paper_pre.join_along_m == 0.0
    kept = front_detector_config("hough", "paper", flecks, keeps=("binarisation",))
    assert kept.preprocess.min_blob_length_m == 1.0 and kept.preprocess.join_along_m == 1.5
    assert ours.profiles.front.x_far_m == 30.0  # the window is a deviation of its own
    both = front_detector_config("hough", "paper", keeps=("binarisation", "windows"))
    assert both.profiles.front.x_far_m == 20.0


def test_the_papers_eq8_is_a_one_millimetre_density():
    """Psi = C P C' + R with the paper's numbers: a 1 cm difference between two models'
    residuals moves their log-odds by ~50, where with ours ((5 cm)^2 plus each tracker's
    variance, which differ by detector) the two stay within a nat of each other."""
    def log_odds(settings) -> float:
        estimator = LaneEstimator(NAMES, settings, reference_x_m=-4.0)
        for k in range(2):
            out = estimator.update({"hough": _lane(0.0), "sliding_window": _lane(0.01)},
                                   _lane(0.0), _ego(k))
        p = out.selection.probabilities
        return float(np.log(p[0] / p[1]))

    paper = estimator_settings(EstimationConfig(mode="paper"))
    ours_psi = replace(paper, residual_covariance="tracker")
    assert log_odds(paper) == pytest.approx(0.5 * 0.01**2 / PAPER_R_M2, rel=0.01)
    assert abs(log_odds(ours_psi)) < 1.0


def test_a_model_without_a_detection_keeps_its_last_one_in_paper_mode():
    """missing_model = "hold": the MMAE compares the model's last detection (a residual, no
    penalty) and the PID reads it when the model is selected; "penalty" compares nothing."""
    paper = estimator_settings(EstimationConfig(mode="paper"))
    for missing, compared in (("hold", True), ("penalty", False)):
        estimator = LaneEstimator(NAMES, replace(paper, missing_model=missing),
                                  reference_x_m=-4.0)
        estimator.update({n: _lane(0.2) for n in NAMES}, _lane(0.2), _ego(0))
        gone = LaneEstimate.invalid("no lane boundary found", x_m=4.0)
        out = None
        for k in (1, 2):
            out = estimator.update({"hough": gone, "sliding_window": _lane(0.2)}, _lane(0.2),
                                   _ego(k))
        assert np.isfinite(out.selection.residuals_m[0]) == compared
    assert out is not None


def test_no_floor_lets_a_model_fall_to_the_smallest_double_and_come_back():
    paper = estimator_settings(EstimationConfig(mode="paper"))
    estimator = LaneEstimator(NAMES, paper, reference_x_m=-4.0)
    for k in range(3):  # hough 10 cm off: 5000 nats a step against it
        out = estimator.update({"hough": _lane(0.1), "sliding_window": _lane(0.0)},
                               _lane(0.0), _ego(k))
    assert out.selection.probabilities[0] == pytest.approx(FINITE_FLOOR)
    for k in range(3, 6):  # now sliding_window is the one off
        out = estimator.update({"hough": _lane(0.0), "sliding_window": _lane(0.1)},
                               _lane(0.0), _ego(k))
    assert out.selection.probabilities[0] > 0.99
