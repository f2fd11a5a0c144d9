"""The estimator's settings, defined once: `LaneEstimator` reads them, and a scenario's
`[estimation]` table is this dataclass plus the loop's own keys (lanekeep/scenario/estimation.py
`EstimationConfig` extends it), so an estimator built on its own runs the loop an `Episode`
runs. Paper mode (lanekeep/driver/paper_mode.py) overrides the choices the paper makes otherwise.

It imports nothing of the estimators: loading a scenario does not load filterpy or scipy.
"""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting
from lanekeep.geometry.lane_width import LANE_WIDTH_PRIOR_M

RESIDUAL_MODES = ("distance_aligned", "one_step_delay")
OUTPUT_MODES = ("select", "fused", "precision")
MODEL_LANES = ("track", "detection")
MMAE_PRIORS = ("uniform", "precision")
OUTPUT_AT = ("lookahead", "nearest_row")  # paper mode sets nearest_row
MMAE_INPUTS = ("track", "detection")  # paper mode sets detection
RESIDUAL_COVARIANCES = ("tracker", "paper")  # paper mode sets paper
MISSING_MODELS = ("penalty", "hold")  # paper mode sets hold
TRACK_REFERENCE_CHECKS = ("starts", "updates")


@dataclass(frozen=True)
class EstimatorSettings:
    """How the trackers, the MMAE and the output policy run (paper 001 §2.3-2.4 and ours).

    Each key's meaning, default and allowed values are at its field (lanekeep/core/setting.py:
    docs/scenario_format.md is written from them and `check_settings` enforces them); the
    comments say why a default is what it is.
    """

    offset_lookahead_m: float = setting(4.0, "Where the front offsets are compared and reported.",
                                        bounds=(0.0, 40.0))
    # Ours compares at the same road position, since one step is not the ~1 s the car needs
    # to drive from the front view to the rear one.
    residual_mode: str = setting("distance_aligned", "distance_aligned: reference and models "
                                 "compared at the same road position; one_step_delay: the paper's "
                                 "eq. 2.", choices=RESIDUAL_MODES)
    # Re-decided 2026-11-27 by paired comparisons over tuning seeds
    # (docs/statistics.md#defaults; the five paper cases x seeds 1000-1004, `lanekeep bench
    # ... --seed 1000 --seeds 5 [--set estimation.output=select]`, `lanekeep compare`): alone,
    # "select" was indistinguishable from "precision" (fused RMSE +0.05 cm [-0.02, +0.13]),
    # but the paper's three choices together (this, `mmae_prior` and
    # `reference_width_tolerance_m`) are worse than ours together: fused RMSE +0.23 cm
    # [+0.13, +0.33], car RMS +0.1 [+0.0, +0.3] cm, and two departures in five occlusion seeds
    # against none. So ours ("precision": `LaneEstimator._precision_fused`).
    output: str = setting("precision", "select = the most probable model's lane (the paper); "
                          "fused = the probability-weighted lane; precision = the lanes fused "
                          "with their tracks' covariances, each weighted by its probability.",
                          choices=OUTPUT_MODES)
    model_lane: str = setting("track", "What a model hands the output: its Kalman track, or its "
                              "own detection when its track's gate accepts it (the paper's PID "
                              "input).", choices=MODEL_LANES)
    # nearest_row: the selected model's track at that row while its detector has nothing.
    output_at: str = setting("lookahead", "Where the output offset is read: on the output lane at "
                             "offset_lookahead_m, or the selected model's own detection at its "
                             "nearest row (the paper's PID input; paper mode sets it).",
                             choices=OUTPUT_AT)
    # "detection": the paper's "the output offsets from both front camera models", with the
    # model's filter giving eq. 8's C P C'.
    mmae_input: str = setting("track", "What the MMAE compares with the reference: each model's "
                              "Kalman track, or its raw detection (the paper's; paper mode sets "
                              "it).", choices=MMAE_INPUTS)
    # At the car each detection's lane is extrapolated to x = 0; otherwise +4 m front and
    # -4 m rear are different road points.
    mmae_at_car: bool = setting(False, "With detection input: compare the models and the "
                                "reference at the car (x = 0), the paper's offset of the vehicle, "
                                "instead of at each detector's own look-ahead.",
                                allowed="true, false")
    # see `LaneEstimator._choose`
    prefer_accepted: bool = setting(True, "Prefer a model whose track accepted this step's "
                                    "detection over a likelier one whose track coasts (the paper "
                                    "takes the argmax; paper mode turns it off).",
                                    allowed="true, false")
    # The width the detectors measure from two boundaries is a running mean; the prior is
    # the common width of motorway lanes (lanekeep/geometry/lane_width.py, the detectors'
    # belief too), not the simulated road's.
    lane_width_prior_m: float = setting(LANE_WIDTH_PRIOR_M, "Lane width that centres a "
                                        "one-boundary detection until the detectors have measured "
                                        "the width from two boundaries.", bounds=(1.0, 10.0))
    reference_std_m: float = setting(0.05, "The rear reference's offset noise in the MMAE's "
                                     "residual density (eq. 8's R): smaller moves the "
                                     "probabilities faster, and with the reference's own errors.",
                                     bounds=(0.001, 1.0))
    # The paper's eq. 8 with its own numbers: R = 1e-6 and P1, P2 "tuned via trial and error"
    # (§2.3), a residual density far narrower than any camera's error: each step's
    # likelihoods then all but pick the model with the smaller |residual|.
    residual_covariance: str = setting(
        "tracker", "Eq. 8's Psi = C P C' + R: tracker = each model's tracker's offset variance "
        "plus reference_std_m squared (ours); paper = the paper's fixed P1, P2 and R = 1e-6 "
        "(m^2; paper mode sets it).", choices=RESIDUAL_COVARIANCES)
    # Every model keeps this much probability so that a failed one can recover; the paper
    # has no floor (paper mode: the smallest normal double, the floor finite arithmetic has).
    probability_floor: float = setting(1e-3, "Least probability every model keeps after each "
                                       "MMAE update.", bounds=(0.0, 0.2))
    # penalty: a model without an offset this step loses probability against every model
    # compared (MMAEConfig.missing_model_log_penalty); hold: its last detection stands in,
    # as the paper's loop carries a value for every model at every step (paper mode).
    missing_model: str = setting(
        "penalty", "A front model without a detection this step: penalty = it loses "
        "probability against the compared ones; hold = its last detection stands in, in the "
        "MMAE and (output_at = nearest_row) as the controller's input.", choices=MISSING_MODELS)
    # On the tuning scenarios the rear pair stays within 16 cm of the running width except
    # where it follows a passing car's edge (the lead van: 4.8% of steps beyond 30 cm).
    # Alone, no check was indistinguishable from 0.2 over tuning seeds (identical but for
    # hundredths of a cm on the paper cases and on occlusion and highway_multilane); kept with
    # `output` above, whose paired comparison of the three choices together favours ours.
    reference_width_tolerance_m: float | None = setting(
        0.2, "A rear reading whose lane is further than this from the width the front detectors "
        "measure is taken as missed (it read a wrong line); paper mode compares every reading.",
        bounds=(0.01, 10.0))
    # A front model that found the next lane's lines (a cut-in car over the car's own paint,
    # a shadow's edge) can keep them for longer than its track coasts (1 s); its lost track
    # then starts on them, or two such models agree and restart theirs, and the loop steers
    # into the next lane (case 3 seed 8, highway_cut_in seed 22, two-model loop, 2026-11-30).
    # The rear camera sees the road the car is on: a front lane that does not meet the
    # reference's at the car is not the car's lane. A quarter of a lane width (midway between
    # a right start, 0, and a pair one line off, half a lane) let a lost track start on a lane
    # 0.85 m off beside a lead van (two-model loop, session 31); a right front lane meets the
    # rear one within centimetres. 0.15 against 0.25, the two-model loop on the 11 tuning
    # scenarios (docs/experiments.md, sessions 31-32): fused RMSE -11.2% [-19.8, -1.7] and
    # -6.0% [-10.6, -1.2] (seeds 1000-1009, 1010-1019), non-inferior both; failed drives
    # 25 -> 16 of 220 (10 kept, 1 lost; McNemar p = 0.012); the default loop equivalent
    # (seeds 1000-1009: fused RMSE +2.4% [-0.8, +5.6], failed 3 -> 3).
    track_start_gate_lane_widths: float | None = setting(
        0.15, "A front track (re)starts from a detection only where its lane meets the rear "
        "reference's at the car (x = 0) within this share of the measured lane width, while "
        "the reference has a lane (after its width check); unset: any detection starts it "
        "(the paper's; paper mode).", bounds=(0.01, 1.0))
    # The check above compares offsets at the car only: a detection whose lane crosses the
    # reference's there with a wrong heading is 1.6 m off 5 m ahead and still passes
    # (sharp_turn seed 3, two-model loop, session 22: the car left its lane). Both lanes'
    # headings at the car are the car's heading in its lane; right detections' gap to the
    # reference's: median 0.010 rad, 99th percentile 0.135 (docs/experiments.md, session 22).
    # Off until decided on the tuning scenarios.
    track_start_gate_heading_rad: float | None = setting(
        None, "With the start check on, a front lane must also run within this heading "
        "(rad) of the rear reference's at the car; unset: offset only.", bounds=(0.01, 1.0))
    # A coasting track's gate widens with its covariance: after most of a second without a
    # detection it accepts a lane 1.3-1.7 m off (case 3 seed 3, two-model loop, 2026-11-30:
    # sliding_window's track took a pair half a lane over at 3.6 s and the car steered by it,
    # 87.5 cm off centre), which the start check above would have refused from a lost track.
    # "updates" asks the start check of every detection a track takes. Decided on the tuning
    # scenarios x 3 seeds (docs/experiments.md, session 19): the default loop identical in 9
    # of 10 and equivalent in the tenth (fused RMSE -0.1% [-0.3, +0.2]); the two-model loop
    # changed only tune_right_turn_shade_bumps, inconclusive (+3.3% [-19.6, +32.8]).
    track_reference_check: str = setting(
        "updates", "Which front detections must meet the rear reference's lane at the car "
        "(track_start_gate_lane_widths): starts = only the one that (re)starts a track; "
        "updates = every one a track takes (a refused one is a miss).",
        choices=TRACK_REFERENCE_CHECKS)
    # In traffic a classical front model can lose the lane for seconds (a cut-in car over
    # the paint); with none left the PID holds the wheel straight and a curve takes the car
    # out of its lane. The rear camera still sees the lane the car is on. Both this and the
    # start check above, 2026-11-30 (docs/experiments.md, session 16): the default loop on
    # the tuning scenarios x 3 seeds equivalent (fused RMSE +0.1% [-0.3, +0.5]; the fallback
    # never taken), the two-model loop's departures there 3 -> 2 of 30 (inconclusive).
    reference_fallback: bool = setting(
        True, "While no front model has a lane, the output is the rear reference's lane "
        "(after its width check) instead of none (the wheel held straight); the paper's "
        "loop has no such output (paper mode).", allowed="true, false")
    # A classical detection's confidence (the share of its window its boundaries cover) says
    # how far off it tends to be: on the tuning scenarios the robust core of hough's and
    # sliding_window's errors is several times wider in their lowest-confidence band than in
    # their highest (estimators/closed_loop_tracker.toml [confidence_noise_by_detector]).
    # Decided on the tuning scenarios x seeds 1000-1004 (docs/experiments.md, session 27): in
    # the default loop not better (fused RMSE +5.0% [-1.2, +11.5] with the classical models'
    # bands alone, non-superior; +2.7% [-3.6, +9.4] with LaneNet's too, and one departure
    # against none); in the two-model loop over seeds 1000-1009 departures 12 -> 8 of 110,
    # McNemar p = 0.34, inconclusive. So off.
    confidence_noise: bool = setting(
        False, "Each detection's R is its detector's times the factor measured for its "
        "confidence band (estimators/closed_loop_tracker.toml), instead of one R for all of "
        "a detector's detections (the paper's; paper mode).", allowed="true, false")
    # Re-decided 2026-11-27 with `output` above: alone, "uniform" was indistinguishable (fused
    # RMSE +0.03 cm [-0.01, +0.06]); together with the paper's other two choices, worse.
    mmae_prior: str = setting("precision", "The MMAE's probabilities before the reference has "
                              "spoken: uniform (the paper's; paper mode keeps it), or each "
                              "model's in proportion to the inverse of its measured offset "
                              "variance at offset_lookahead_m (its tracker's R).",
                              choices=MMAE_PRIORS)
    lane_width_gain: float = setting(0.05, "Weight of each two-boundary width measurement in the "
                                     "running mean.", allowed="(0, 1]")
    lane_width_range_m: tuple[float, float] = setting(
        (2.5, 5.0), "Plausible lane widths [low, high]; measurements outside are ignored.",
        allowed="0 < low < high")

    def __post_init__(self) -> None:
        """A misspelt choice would otherwise fall through to some other branch silently."""
        check_settings(self)
        if not 0.0 < self.lane_width_gain <= 1.0:
            raise InvalidValue("lane_width_gain", f"must be in (0, 1], got {self.lane_width_gain}")
        low, high = self.lane_width_range_m
        if not 0.0 < low < high:
            raise InvalidValue("lane_width_range_m",
                               f"must be two widths 0 < low < high, got {self.lane_width_range_m}")
