"""The paper's own loop (paper 001 §2.2-2.5) as a mode of the driver: `[estimation] mode =
"paper"` in a scenario, or `--mode paper` on `lanekeep run` / `lanekeep bench`.

What changes from our default loop, and why the default differs:
  - residuals: the reference compared with each model's detection one step earlier (eq. 2,
    "one_step_delay"), both as "the offset of the vehicle" (each lane read at the car, x = 0);
    ours compares each model's Kalman track, carried by odometry to the road point the rear
    camera sees now ("distance_aligned"), since one step is not the ~1 s the car needs to
    drive from the front view to the rear one;
  - selection: the likeliest model (the paper's decision unit); ours passes over a likelier
    model whose track coasts this step for one whose track accepted its detection;
  - PID input: the selected model's own detection at its nearest row (the paper feeds the
    model's offset to eq. 9); ours reads the selected model's Kalman track at 8 m and adds its
    heading;
  - controller: eq. 9 with Table 2's straight / curvy gain shape and no feed-forward
    (lanekeep/control/pid.py `PaperGains` documents the unit conversion); ours derives gains from
    a time constant and adds a curvature feed-forward;
  - regions of interest: model #1 (Hough) looks far, model #2 (sliding windows) looks near and
    narrow ("its ROI is larger and has a better performance in long-distance detection";
    model #2 "has a smaller ROI"); ours gives both the same 4-20 m window;
  - binarisation: the paper's fixed thresholds (detectors/paper_thresholds.py: model #1 a
    brightness test, model #2 Sobel-x, saturation and hue, at the values of the authors'
    code but for the white level, set for this world's paint), not our tuned tests against
    the road beside the paint, and without our image stage's additions (vehicle masking,
    rain-streak removal, the speckle and fill tests);
  - eq. 8: the paper's R = 1e-6 and fixed P1, P2 (ours: each tracker's C P C' and (5 cm)^2);
  - probabilities: no floor beyond finite arithmetic, and a model without a detection keeps
    its last one (ours: a floor of 1e-3 and a penalty for a missing model).

Each of these is a named deviation (lanekeep/scenario/estimation.py `PAPER_DEVIATIONS`):
`[estimation] paper_keeps = [NAME, ...]` keeps ours for it in paper mode, so that what each
one changes can be measured on its own.
Left as ours in both modes, for the paper gives no rule: how the boundaries are found in the
binary bird's-eye view (Hough segments grown into boundaries, sliding windows) and what
counts as a lane boundary (detectors/config.py LaneRules); the control period (0.1 s; the
authors' loop slept 0.5 s of wall time between frames, at a speed the paper does not give).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lanekeep.detectors.config import DetectorsConfig, load_config
from lanekeep.estimators.lane_estimator import EstimatorSettings
from lanekeep.estimators.roll import RollCompensation
from lanekeep.scenario.estimation import EstimationConfig

# Front ground windows (x_near_m, x_far_m, y_half_m) of the paper's two models. Model #2's
# 4-12 m x +-3 m holds the ego lane's two boundaries (+-1.85 m) on a straight, and loses the
# outer one within 10 m in a 40 m-radius turn, as the paper's small trapezoid does.
PAPER_WINDOWS: dict[str, tuple[float, float, float]] = {
    "hough": (4.0, 30.0, 6.0),
    "sliding_window": (4.0, 12.0, 3.0),
}

# The floor finite arithmetic has: the smallest normal double (the MMAE works in logs).
FINITE_FLOOR = float(np.finfo(float).tiny)

# What paper mode sets in the estimator, per named deviation (scenario/estimation.py lists the
# names and what ours does instead).
ESTIMATOR_CHOICES: dict[str, dict[str, object]] = {
    "residuals": {"residual_mode": "one_step_delay", "mmae_input": "detection",
                  "mmae_at_car": True},
    "residual_covariance": {"residual_covariance": "paper"},
    "probability_floor": {"probability_floor": FINITE_FLOOR, "missing_model": "hold"},
    "mmae_prior": {"mmae_prior": "uniform"},
    "reference_width_check": {"reference_width_tolerance_m": None},
    "track_start_check": {"track_start_gate_lane_widths": None},
    "reference_fallback": {"reference_fallback": False},
    "confidence_noise": {"confidence_noise": False},
    "output": {"output": "select", "prefer_accepted": False},
    "pid_input": {"model_lane": "detection", "output_at": "nearest_row"},
}


def estimator_settings(est: EstimationConfig) -> EstimatorSettings:
    """The estimator's settings of a scenario; paper mode overrides its choices."""
    settings = est.estimator_settings()
    for deviation, choices in ESTIMATOR_CHOICES.items():
        if est.runs_paper(deviation):
            settings = replace(settings, **choices)
    return settings


def roll_compensation(est: EstimationConfig) -> RollCompensation:
    """The scenario's body roll compensation; the paper's loop has none."""
    if est.runs_paper("roll_compensation"):
        return RollCompensation()
    return RollCompensation(est.roll_gradient_deg_per_mps2,
                            (("front", est.roll_lever_front_m), ("rear", est.roll_lever_rear_m)))


def front_detector_config(name: str, mode: str, base: DetectorsConfig | None = None,
                          keeps: tuple[str, ...] = ()) -> DetectorsConfig | None:
    """The detectors config a front model runs with: the shipped one (None), or in paper
    mode the same with the model's own window and the paper's binarisation, less what
    `keeps` names of our deviations ("windows", "binarisation")."""
    if mode != "paper" or name not in PAPER_WINDOWS:
        return base
    config = base or load_config()
    if "windows" not in keeps:
        near, far, half = PAPER_WINDOWS[name]
        front = replace(config.profiles.front, x_near_m=near, x_far_m=far, y_half_m=half,
                        blind_m=0.0)
        config = replace(config, profiles=replace(config.profiles, front=front))
    if "binarisation" not in keeps:
        # The paper's fixed thresholds, and none of our image stage's additions: no vehicle
        # mask, no rain-streak opening or removal, no speckle, fill or blob test, no dots
        # joined along the road.
        pre = replace(config.preprocess, vehicle_dark_ratio=0.0, destreak_width_px=0.0,
                      streak_min_rows=0, min_coherence=0.0, max_fill=1.0,
                      max_paint_width_m=0.0, min_blob_length_m=0.0, join_along_m=0.0)
        config = replace(config, preprocess=pre,
                         hough=replace(config.hough, binarisation="paper", fallback=""),
                         sliding_window=replace(config.sliding_window, binarisation="paper",
                                                fallback=""))
    return config
