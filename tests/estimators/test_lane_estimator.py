"""The closed loop's estimator behind one call: centring, tracking, choice, timing laps."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.detectors.base import LaneEstimate
from lanekeep.estimators.lane_estimator import EgoMotion, EstimatorSettings, LaneEstimator

WIDTH = 3.7
NAMES = ["hough", "sliding_window"]
# These unit tests were written for the paper's choices (the likeliest model's lane, equal
# starting probabilities, every reference reading compared); a test of another choice says so.
PAPER_CHOICES = {"output": "select", "mmae_prior": "uniform", "reference_width_tolerance_m": None}


def _settings(**overrides) -> EstimatorSettings:
    return EstimatorSettings(**{"lane_width_prior_m": WIDTH, **PAPER_CHOICES, **overrides})


def _lane(c0: float, heading: float = 0.0) -> LaneEstimate:
    """A detection of a straight lane whose centre is at y = c0 (both boundaries)."""
    left = np.array([c0 + WIDTH / 2, heading, 0.0])
    right = np.array([c0 - WIDTH / 2, heading, 0.0])
    return LaneEstimate(valid=True, offset_m=-c0, x_m=4.0, left=left, right=right)


def _ego(k: int, speed: float = 15.0) -> EgoMotion:
    return EgoMotion(0.1, speed, 0.0, 0.0, (speed * 0.1 * k, 0.0, 0.0), speed * 0.1 * (k + 1))


def _estimator() -> LaneEstimator:
    return LaneEstimator(NAMES, _settings(), reference_x_m=-4.0)


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

    from lanekeep.core.config_io import ConfigError
    from lanekeep.estimators.lane_estimator import TRACKER_TOML, closed_loop_tracker

    text = resources.files("lanekeep.estimators").joinpath(TRACKER_TOML).read_text()
    tuning = closed_loop_tracker(text)
    config = tuning.default
    assert config.coast_with_rates is False
    data = tomllib.loads(text)
    measured = np.asarray(data["measured_coefficient_covariance"])
    np.testing.assert_allclose(config.coefficient_r, data["r_scale"] * measured)
    own = data["measured_coefficient_covariance_by_detector"]
    assert set(own) == {"hough", "sliding_window", "lanenet"}
    for name, covariance in own.items():
        np.testing.assert_allclose(tuning.for_detector(name).coefficient_r,
                                   data["r_scale"] * np.asarray(covariance))
        assert tuning.for_detector(name).coast_with_rates is False
    assert tuning.for_detector("my_plugin:Detector") is config
    with pytest.raises(ConfigError, match="by_detector.lanenet"):
        closed_loop_tracker(text.replace("\nlanenet = [", "\nlanenet = [[1.0], ", 1))
    with pytest.raises(ConfigError, match="tracker.c1_accel_psd"):
        closed_loop_tracker(text.replace("[tracker]\n", "[tracker]\nc1_accel_psd = 1e-3\n", 1))
    with pytest.raises(ConfigError, match="r_scale"):
        closed_loop_tracker(text.replace("r_scale = 4.0", ""))
    with pytest.raises(ConfigError, match="gate_probability"):
        closed_loop_tracker(text + "gate_probability = 1.5\n")


def test_paper_settings_hand_on_the_selected_detection_at_its_own_row():
    """Paper mode's PID input is the selected model's detection as the detector reported it
    (offset and look-ahead), even when its track's gate rejects it; the MMAE compares every
    offset at the car (x = 0), the reference's too."""
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig

    settings = estimator_settings(EstimationConfig(mode="paper"))
    assert (settings.residual_mode, settings.model_lane, settings.output_at) == (
        "one_step_delay", "detection", "nearest_row")
    from lanekeep.estimators.lane_estimator import shipped_tracker

    # one R for both models, so that their probabilities stay equal until the jump
    estimator = LaneEstimator(NAMES, settings, reference_x_m=-4.0,
                              tracker=shipped_tracker().default)
    for k in range(10):
        estimator.update({n: _lane(0.0) for n in NAMES}, _lane(0.0), _ego(k))
    jump = LaneEstimate(valid=True, offset_m=-1.5, x_m=5.0, left=np.array([3.35, 0.0, 0.0]),
                        right=np.array([-0.35, 0.0, 0.0]))
    out = estimator.update({"hough": jump, "sliding_window": _lane(0.0)}, _lane(0.0), _ego(10))
    assert out.tracker_status == {"hough": "gated", "sliding_window": "updated"}
    assert out.selected == 0  # the argmax (equal so far: the first), not the accepted one
    assert (out.offset_m, out.offset_x_m) == (-1.5, 5.0)
    assert out.reference_x_m == 0.0


def test_each_detector_tracks_with_its_own_measured_noise():
    """The shipped tuning gives every measured detector its own R (a plug-in the pooled one),
    and the corroboration between models uses each one's: a steady detector's track follows
    its detections more closely than a noisy detector's track follows the same detections."""
    from lanekeep.estimators.lane_estimator import shipped_tracker

    names = ["hough", "lanenet", "mod:Plugin"]
    estimator = LaneEstimator(names, _settings(), -4.0)
    for name in names:
        assert estimator.trackers[name].config is shipped_tracker().for_detector(name)
    assert estimator.trackers["mod:Plugin"].config is shipped_tracker().default
    for k in range(30):
        estimator.update({n: _lane(0.0) for n in names}, _lane(0.0), _ego(k))
    out = estimator.update({n: _lane(0.1) for n in names}, _lane(0.0), _ego(30))
    moved = {n: out.tracked[n][0] for n in names}
    assert moved["lanenet"] > moved["hough"] > 0.0


def test_precision_output_equals_a_direct_computation():
    """output = "precision": the lane is (sum_n p_n P_n^-1)^-1 sum_n p_n P_n^-1 c_n, with p the
    MMAE's probabilities and P_n each track's coefficient covariance."""
    names = ["hough", "sliding_window", "lanenet"]
    settings = _settings(output="precision")
    estimator = LaneEstimator(names, settings, reference_x_m=-4.0)
    lanes = {"hough": 0.05, "sliding_window": -0.03, "lanenet": 0.01}
    for k in range(25):
        jitter = 0.01 * (-1) ** k
        out = estimator.update({n: _lane(c + jitter * (n == "hough")) for n, c in lanes.items()},
                               _lane(0.0), _ego(k))
    p = out.selection.probabilities
    info = [pn * np.linalg.inv(estimator.trackers[n].P[:3, :3])
            for pn, n in zip(p, names, strict=True)]
    expected = np.linalg.solve(sum(info), sum(w @ out.tracked[n]
                                              for w, n in zip(info, names, strict=True)))
    np.testing.assert_allclose(out.centre, expected, rtol=1e-9, atol=1e-12)
    assert min(out.tracked[n][0] for n in names) < out.centre[0] < max(
        out.tracked[n][0] for n in names)
    fused = LaneEstimator(names, _settings(output="fused"),
                          reference_x_m=-4.0)
    for k in range(25):
        jitter = 0.01 * (-1) ** k
        plain = fused.update({n: _lane(c + jitter * (n == "hough")) for n, c in lanes.items()},
                             _lane(0.0), _ego(k))
    assert not np.allclose(plain.centre, out.centre)  # the variances change the weights


def test_the_reference_noise_setting_reaches_the_mmae():
    """Eq. 8's R comes from the scenario: a noisier reference moves the probabilities less."""
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig

    spreads = []
    for std in (0.02, 0.05):
        settings = estimator_settings(EstimationConfig(reference_std_m=std, mmae_prior="uniform"))
        assert settings.reference_std_m == std
        estimator = LaneEstimator(NAMES, settings, -4.0)
        assert estimator.mmae.config.reference_std_m == std
        z = [0.0, 0.03]  # residuals of 0 and 3 cm against a reference at 0
        out = estimator.mmae.step(0.0, z, [1e-4, 1e-4])
        spreads.append(out.probabilities[0] - out.probabilities[1])
    assert spreads[0] > spreads[1] > 0


def test_the_precision_prior_weighs_each_model_by_its_measured_offset_variance():
    """p_n(0) proportional to 1 / (C R_n C') at the output's look-ahead, from each detector's own
    tracker R; "uniform" is the paper's equal start."""
    names = ["hough", "sliding_window", "lanenet"]
    settings = _settings(mmae_prior="precision")
    estimator = LaneEstimator(names, settings, -4.0)
    c = np.array([1.0, 4.0, 16.0])
    inverse = np.array([1.0 / (c @ np.asarray(estimator.tracker_configs[n].coefficient_covariance)
                               @ c) for n in names])
    np.testing.assert_allclose(estimator.mmae.probabilities, inverse / inverse.sum())
    assert np.argmax(estimator.mmae.probabilities) == 2  # lanenet: the steadiest near offset
    uniform = LaneEstimator(names, _settings(), -4.0)
    np.testing.assert_allclose(uniform.mmae.probabilities, np.full(3, 1.0 / 3.0))


def _pair(c0: float, width: float) -> LaneEstimate:
    """A straight lane centred at y = c0 whose two boundaries are `width` apart."""
    return LaneEstimate(valid=True, offset_m=-c0, x_m=-4.0, left=np.array([c0 + width / 2, 0, 0]),
                        right=np.array([c0 - width / 2, 0, 0]))


def test_a_reference_that_reads_a_lane_of_the_wrong_width_is_taken_as_missed():
    """A rear pair 0.5 m narrower than the lane the front detectors measure has read a wrong
    line (a passing car's edge): the MMAE is not updated with it and an event says why. One
    within the tolerance is compared; without a tolerance (the paper's) every one is."""
    settings = _settings(reference_width_tolerance_m=0.2)
    estimator = LaneEstimator(NAMES, settings, reference_x_m=-4.0)
    for k in range(10):  # 15 m: the models' history reaches where the reference looks
        estimator.update({n: _lane(0.0) for n in NAMES}, _pair(0.0, WIDTH), _ego(k))
    before = estimator.mmae.probabilities
    out = estimator.update({"hough": _lane(0.0), "sliding_window": _lane(0.2)},
                           _pair(0.25, WIDTH - 0.5), _ego(10))
    assert not out.selection.updated and out.selection.reference_m is None
    np.testing.assert_allclose(out.selection.probabilities, before)
    assert any("reference ignored" in e and "3.20 m" in e for e in out.events)
    out = estimator.update({"hough": _lane(0.0), "sliding_window": _lane(0.2)},
                           _pair(0.0, WIDTH - 0.1), _ego(11))
    assert out.selection.updated and not any("ignored" in e for e in out.events)
    paper = LaneEstimator(NAMES, _settings(), -4.0)
    for k in range(10):
        paper.update({n: _lane(0.0) for n in NAMES}, _pair(0.0, WIDTH), _ego(k))
    assert paper.update({n: _lane(0.0) for n in NAMES}, _pair(0.25, WIDTH - 0.5),
                        _ego(10)).selection.updated


def test_the_reference_width_tolerance_is_a_scenario_setting_paper_mode_leaves_out():
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig, InvalidValue

    assert estimator_settings(EstimationConfig()).reference_width_tolerance_m == 0.2
    chosen = EstimationConfig(reference_width_tolerance_m=0.3)
    assert estimator_settings(chosen).reference_width_tolerance_m == 0.3
    paper = EstimationConfig(mode="paper", reference_width_tolerance_m=0.3)
    assert estimator_settings(paper).reference_width_tolerance_m is None
    with pytest.raises(InvalidValue, match="reference_width_tolerance_m"):
        EstimationConfig(reference_width_tolerance_m=0.0)


def test_a_misspelt_estimator_choice_is_refused_not_taken_for_another():
    with pytest.raises(ValueError, match="residual_mode"):
        EstimatorSettings(residual_mode="distance-aligned")
    with pytest.raises(ValueError, match="output"):
        EstimatorSettings(output="precise")
    assert EstimatorSettings(output="fused", mmae_input="detection").output == "fused"


def test_an_estimator_built_on_its_own_runs_the_loop_an_episode_runs():
    """One definition of the settings: the scenario's [estimation] defaults are the
    estimator's own, so `EstimatorSettings()` is what a default Episode runs."""
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig

    assert EstimationConfig().estimator_settings() == EstimatorSettings()
    assert estimator_settings(EstimationConfig()) == EstimatorSettings()
    assert EstimatorSettings().output == "precision"  # re-decided over seeds: docs/statistics.md


def test_a_track_starts_only_on_a_lane_that_meets_the_rear_reference_at_the_car():
    """A front model that reads the next lane (its centre half a lane width off, a pair one
    line over) does not start its track while the rear reference sees the car's lane; the
    model beside it that agrees with the reference does, and an event says why. With no
    reference lane to ask, the same detection starts the track, as it always did."""
    estimator = LaneEstimator(NAMES, _settings(), reference_x_m=-4.0)
    for k in range(5):
        out = estimator.update({"hough": _lane(WIDTH / 2), "sliding_window": _lane(0.05)},
                               _pair(0.0, WIDTH), _ego(k))
        assert out.tracked["hough"] is None and out.tracked["sliding_window"] is not None
    assert any("hough: track start refused: its lane 1.85 m" in e for e in out.events)
    out = estimator.update({"hough": _lane(0.3), "sliding_window": _lane(0.05)},
                           _pair(0.0, WIDTH), _ego(5))
    assert out.tracker_status["hough"] == "initialized"  # 0.3 m: within 0.15 of a lane (0.56 m)
    blind = LaneEstimator(NAMES, _settings(), reference_x_m=-4.0)
    out = blind.update({"hough": _lane(WIDTH / 2), "sliding_window": _lane(0.05)},
                       LaneEstimate.invalid("no lane"), _ego(0))
    assert out.tracker_status["hough"] == "initialized"


def test_two_models_that_agree_on_the_next_lane_do_not_restart_their_tracks():
    """Both front models jump to the next lane's lines together (a cut-in car over the
    car's own paint): they corroborate each other, but the rear reference still sees the
    car's lane, so the tracks coast on instead of restarting there: gated, where only a
    start is checked; missed (refused before the gate), where every update is. Without the
    check (paper mode) they restart."""
    def run(gate, check="updates"):
        settings = _settings(track_start_gate_lane_widths=gate, track_reference_check=check)
        estimator = LaneEstimator(NAMES, settings, -4.0)
        for k in range(10):
            estimator.update({n: _lane(0.0) for n in NAMES}, _pair(0.0, WIDTH), _ego(k))
        return estimator.update({n: _lane(WIDTH / 2) for n in NAMES}, _pair(0.0, WIDTH),
                                _ego(10))

    for check, status in (("starts", "gated"), ("updates", "missed")):
        checked = run(0.25, check)
        assert set(checked.tracker_status.values()) == {status}
        assert abs(checked.centre[0]) < 0.05
    unchecked = run(None)
    assert set(unchecked.tracker_status.values()) == {"restarted"}


def _after_a_coast(settings, detection: LaneEstimate):
    """Both tracks held on the lane for 1 s, then 0.9 s without a detection (the gate widens),
    then `detection` for sliding_window alone: the estimator's output of that step."""
    estimator = LaneEstimator(NAMES, settings, -4.0)
    for k in range(10):
        estimator.update({n: _lane(0.0) for n in NAMES}, _pair(0.0, WIDTH), _ego(k))
    for k in range(10, 19):
        estimator.update({n: LaneEstimate.invalid("no lane") for n in NAMES},
                         _pair(0.0, WIDTH), _ego(k))
    return estimator.update({"hough": LaneEstimate.invalid("no lane"),
                             "sliding_window": detection}, _pair(0.0, WIDTH), _ego(19))


def test_with_every_update_checked_a_coasting_track_takes_no_lane_the_reference_disowns():
    """A coasting track's gate widens with its covariance, so after most of a second it takes
    a lane well off the one it held (case 3 seed 3, two-model loop: a pair half a lane over).
    With `track_reference_check = "updates"` such a detection must meet the rear reference's
    lane at the car, as a start must: it is a miss and the track coasts on; a detection that
    meets it is taken. (A gate of a tenth of a lane, so that the coasted gate can reach past
    it here.)"""
    def after_a_coast(check: str, c0: float):
        return _after_a_coast(_settings(track_reference_check=check,
                                        track_start_gate_lane_widths=0.1), _lane(c0))

    assert after_a_coast("starts", 0.6).tracker_status["sliding_window"] == "updated"
    refused = after_a_coast("updates", 0.6)
    assert refused.tracker_status["sliding_window"] == "missed"
    assert abs(refused.tracked["sliding_window"][0]) < 0.05
    assert "sliding_window: track update refused: its lane 0.60 m from the reference's at " \
           "the car" in refused.events
    assert after_a_coast("updates", 0.2).tracker_status["sliding_window"] == "updated"
    with pytest.raises(ValueError, match="track_reference_check"):
        EstimatorSettings(track_reference_check="every")


def test_with_the_heading_check_a_lane_that_crosses_the_reference_at_the_car_is_refused():
    """A detection whose lane meets the reference's at the car but runs off at 0.3 rad
    (1.5 m off 5 m ahead: sharp_turn seed 3's wrong line) passes the offset check alone; with
    `track_start_gate_heading_rad` it is refused like a lane a line over, and the event gives
    both gaps. A lane at the reference's heading is still taken, and with the check unset
    (the default) nothing changes."""
    def after_a_coast(heading_gate, heading: float):
        return _after_a_coast(_settings(track_start_gate_heading_rad=heading_gate),
                              _lane(0.0, heading))

    refused = after_a_coast(0.15, 0.3)
    assert refused.tracker_status["sliding_window"] == "missed"
    assert "sliding_window: track update refused: its lane 0.00 m and 0.291 rad from the " \
           "reference's at the car" in refused.events
    assert after_a_coast(0.15, 0.05).tracker_status["sliding_window"] == "updated"
    assert after_a_coast(None, 0.3).tracker_status["sliding_window"] != "missed"
    assert EstimatorSettings().track_start_gate_heading_rad is None


def test_the_track_start_check_is_a_setting_paper_mode_leaves_out():
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig, InvalidValue

    assert estimator_settings(EstimationConfig()).track_start_gate_lane_widths == 0.15
    assert estimator_settings(EstimationConfig()).track_reference_check == "updates"
    paper = EstimationConfig(mode="paper")
    assert estimator_settings(paper).track_start_gate_lane_widths is None
    kept = EstimationConfig(mode="paper", paper_keeps=("track_start_check",))
    assert estimator_settings(kept).track_start_gate_lane_widths == 0.15
    with pytest.raises(InvalidValue, match="track_start_gate_lane_widths"):
        EstimationConfig(track_start_gate_lane_widths=2.0)


def test_with_no_front_lane_the_fallback_steers_by_the_rear_reference():
    """Both front models lose the lane (a cut-in car over the paint): with the fallback on,
    the output is the rear reference's lane, where without it there is none (the wheel
    held straight); a reference of the wrong width (its width check) is no fallback."""
    def step(fallback: bool, reference: LaneEstimate):
        estimator = LaneEstimator(NAMES, _settings(reference_fallback=fallback,
                                                   reference_width_tolerance_m=0.2), -4.0)
        none = LaneEstimate.invalid("paint hidden")
        return estimator.update({n: none for n in NAMES}, reference, _ego(0))

    out = step(True, _pair(0.3, WIDTH))
    np.testing.assert_allclose(out.centre, [0.3, 0.0, 0.0])
    assert abs(out.offset_m - (-0.3)) < 1e-9
    assert "no front lane: the output is the rear reference's" in out.events
    assert step(False, _pair(0.3, WIDTH)).centre is None
    assert step(True, _pair(0.3, WIDTH - 0.5)).centre is None


def test_the_reference_fallback_is_a_setting_paper_mode_leaves_out():
    from lanekeep.driver.paper_mode import estimator_settings
    from lanekeep.scenario.schema import EstimationConfig

    assert estimator_settings(EstimationConfig(reference_fallback=True)).reference_fallback
    paper = EstimationConfig(mode="paper", reference_fallback=True)
    assert estimator_settings(paper).reference_fallback is False
