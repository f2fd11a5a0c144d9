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
  - binarisation: per pixel in the image, as the paper's models threshold it (model #1 a
    brightness test, model #2 Sobel-x, saturation and hue), whatever a detectors file
    chooses for the default mode (which may find paint in the bird's-eye view: [classical],
    detectors/ridge.py and detectors/edge_pairs.py, opt-in).
"""

from __future__ import annotations

from dataclasses import replace

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


def estimator_settings(est: EstimationConfig) -> EstimatorSettings:
    """The estimator's settings of a scenario; paper mode overrides its choices."""
    settings = est.estimator_settings()
    if est.mode != "paper":
        return settings
    return replace(settings, residual_mode="one_step_delay", output="select",
                   model_lane="detection", output_at="nearest_row", mmae_input="detection",
                   mmae_at_car=True, prefer_accepted=False, mmae_prior="uniform",
                   reference_width_tolerance_m=None)


def roll_compensation(est: EstimationConfig) -> RollCompensation:
    """The scenario's body roll compensation; the paper's loop has none."""
    if est.mode == "paper":
        return RollCompensation()
    return RollCompensation(est.roll_gradient_deg_per_mps2,
                            (("front", est.roll_lever_front_m), ("rear", est.roll_lever_rear_m)))


def front_detector_config(name: str, mode: str,
                          base: DetectorsConfig | None = None) -> DetectorsConfig | None:
    """The detectors config a front model runs with: the shipped one (None), or in paper
    mode the same with the model's own window and the paper's per-pixel binarisation."""
    if mode != "paper" or name not in PAPER_WINDOWS:
        return base
    base = base or load_config()
    near, far, half = PAPER_WINDOWS[name]
    front = replace(base.profiles.front, x_near_m=near, x_far_m=far, y_half_m=half, blind_m=0.0)
    return replace(base, profiles=replace(base.profiles, front=front),
                   hough=replace(base.hough, binarisation="image"),
                   sliding_window=replace(base.sliding_window, binarisation="image"))
