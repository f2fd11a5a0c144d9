"""The `[estimation]` table of a scenario: which detectors run, the MMAE's reference, how the
output is formed, and the estimation modes' default front detectors.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import setting
from lanekeep.estimators.settings import EstimatorSettings

ESTIMATION_MODES = ("default", "paper")
CAMERAS = ("front", "rear")
# The front models of each estimation mode when a scenario names none: our loop adds the
# learned model (detectors/lanenet.py) to the paper's two classical ones; the paper's loop
# keeps its two.
DEFAULT_FRONT_DETECTORS = {"default": ("hough", "sliding_window", "lanenet"),
                           "paper": ("hough", "sliding_window")}
# Where our loop departs from the paper's, one name each: paper mode takes the paper's choice
# for all of them unless `paper_keeps` names one (lanekeep/driver/paper_mode.py applies them).
PAPER_DEVIATIONS: dict[str, str] = {
    "residuals": "ours: each model's track carried by odometry to the road point the rear "
                 "camera sees; paper: each detection one step earlier, at the car (eq. 2)",
    "residual_covariance": "ours: each tracker's C P C' plus (5 cm)^2; paper: its fixed P1, "
                           "P2 and R = 1e-6 (eq. 8)",
    "probability_floor": "ours: every model keeps 1e-3 and a missing model is penalised; "
                         "paper: no floor beyond finite arithmetic, a missing model's last "
                         "detection stands in",
    "mmae_prior": "ours: probabilities start by each model's measured precision; paper: equal",
    "reference_width_check": "ours: a rear reading of the wrong lane width is ignored; "
                             "paper: every reading counts",
    "track_start_check": "ours: a front track starts, and takes a detection, only from a "
                         "lane that meets the rear reference's at the car; paper: any "
                         "detection starts it and its gate alone decides",
    "reference_fallback": "ours: with no front lane the output is the rear reference's; "
                          "paper: none, the wheel held straight",
    "confidence_noise": "ours: a detection's R follows its confidence band; paper: one "
                        "noise for all of a model's detections",
    "output": "ours: the tracks fused by precision and probability; paper: the likeliest model",
    "pid_input": "ours: the output lane at the control look-ahead with its heading; paper: the "
                 "selected model's detection at its nearest row",
    "controller": "ours: gains from a time constant, curvature feed-forward; paper: eq. 9 "
                  "with Table 2's gains",
    "roll_compensation": "ours: body roll taken out of each camera's lane; paper: none",
    "windows": "ours: both front models 4-20 m; paper: model #1 4-30 m, model #2 4-12 m x +-3 m",
    "binarisation": "ours: paint against the road beside it, vehicles masked, rain removed; "
                    "paper: fixed thresholds (detectors/paper_thresholds.py)",
}


@dataclass(frozen=True)
class EstimationConfig(EstimatorSettings):
    """Which detectors run, which one is the MMAE reference, and how the output is formed.

    The estimator's own keys (residual_mode, output, model_lane, mmae_prior, ...) and their
    defaults are `EstimatorSettings`' (estimators/settings.py), defined once; the keys below
    are the loop's. The paper runs two front models and a rear-camera reference; residuals
    compare the reference with the models one step earlier (eq. 2) or, our default, at the
    same road position.
    """

    # "paper": the paper's own loop to the letter (lanekeep/driver/paper_mode.py): its
    # fixed-threshold detectors and windows, one-step-delay residuals at the car, eq. 8 with its
    # R and P, no floor, the likeliest model's nearest-row detection into eq. 9 with Table 2's
    # gains; every difference from ours is a PAPER_DEVIATIONS name that `paper_keeps` can keep.
    # "default" is our loop with its improvements.
    mode: str = setting("default", "default = our loop; paper = the paper's own loop to the "
                        "letter (its detectors, eq. 2-8 and PID; paper_keeps keeps named "
                        "deviations of ours).",
                        choices=ESTIMATION_MODES)
    # None: the mode's own (DEFAULT_FRONT_DETECTORS), filled in at construction.
    front_detectors: tuple[str, ...] | None = setting(
        None, "The MMAE's models, front camera, in order. Not set: the mode's own, hough, "
        "sliding_window and lanenet (default) or the paper's hough and sliding_window (paper).",
        allowed="registered names, package.module:Class, entry points")
    # The learned detector on the rear camera, as the paper's reference is a learned one
    # (CLRNet); model #2 ("sliding_window") there errs with front model #2 and fails in traffic.
    # "rowanchor" (#58) is a rear model that shares no weights, architecture or training data
    # with any front model; the default stays until a closed-loop comparison says otherwise.
    reference_detector: str = setting(
        "lanenet", "The MMAE's reference (the paper's observer). rowanchor: #58's row-anchor "
        "network, independent of every front model (docs/observer.md).",
        allowed="as front_detectors")
    reference_camera: str = setting("rear", "Camera the reference detector looks through.",
                                    choices=CAMERAS)
    paper_keeps: tuple[str, ...] = setting(
        (), "In paper mode, the deviations of ours to keep (each runs the paper's choice "
        "otherwise): " + ", ".join(PAPER_DEVIATIONS) + ". See docs/paper_mode.md.",
        allowed="names from the list")
    control_lookahead_m: float = setting(8.0, "Where the controller reads the chosen lane.",
                                         bounds=(0.0, 40.0))
    # Body roll compensation (estimators/roll.py; default mode only): the car's roll per m/s^2
    # of lateral acceleration (a suspension constant; 0 turns it off) and each camera's offset
    # error per radian of roll, both measured by tools/measure_roll_coupling.py on the tuning
    # scenarios.
    roll_gradient_deg_per_mps2: float = setting(0.71, "The car's body roll per m/s^2 of lateral "
                                                "acceleration, with which each camera's lane is "
                                                "corrected for roll from the lateral "
                                                "accelerometer (default mode; 0 = off).",
                                                unit="deg/(m/s^2)", bounds=(0.0, 5.0))
    roll_lever_front_m: float = setting(2.4, "Front camera's offset error per radian of body "
                                        "roll.", bounds=(-10.0, 10.0))
    roll_lever_rear_m: float = setting(2.5, "Rear camera's offset error per radian of body roll.",
                                       bounds=(-10.0, 10.0))

    def __post_init__(self):
        super().__post_init__()  # the estimator's checks, and every field's bounds and choices
        if self.front_detectors is None:
            object.__setattr__(self, "front_detectors", DEFAULT_FRONT_DETECTORS[self.mode])
        if not self.front_detectors:
            raise InvalidValue("front_detectors", "at least one front detector is needed")
        unknown = [name for name in self.paper_keeps if name not in PAPER_DEVIATIONS]
        if unknown:
            raise InvalidValue("paper_keeps", f"unknown deviation {unknown[0]!r}; one of "
                                              f"{', '.join(PAPER_DEVIATIONS)}")

    def runs_paper(self, deviation: str) -> bool:
        """Whether the paper's choice is taken for `deviation` (a `PAPER_DEVIATIONS` name): in
        paper mode, unless `paper_keeps` names it."""
        if deviation not in PAPER_DEVIATIONS:
            raise KeyError(f"unknown deviation {deviation!r}")
        return self.mode == "paper" and deviation not in self.paper_keeps

    def estimator_settings(self) -> EstimatorSettings:
        """The estimator's part of this table, as the estimator's own type."""
        return EstimatorSettings(**{f.name: getattr(self, f.name)
                                    for f in dataclasses.fields(EstimatorSettings)})
