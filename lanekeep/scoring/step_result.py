"""One control period as it happened (`StepResult`: what the car saw and believed, what it
commanded, how that scored against the truth) and its first half (`Percept`: what the car had
before it acted). Typed here, below the recorder and the faces and above the driver whose
belief they carry, so that the recorder, the metrics, the plots, the agent faces and the
tools all read the same records."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lanekeep.core.signals import VehicleSignals
from lanekeep.core.steps import Observation
from lanekeep.detectors.base import LaneEstimate
from lanekeep.driver.driver import Belief
from lanekeep.scoring.safety import StepSafety
from lanekeep.scoring.step_truth import StepTruth


@dataclass(frozen=True)
class StepResult:
    """Everything one control step produced (what the recorder and the dm_env wrapper see)."""

    index: int
    time_s: float
    frames: dict[str, np.ndarray]
    estimates: dict[str, LaneEstimate]
    tracked: dict[str, np.ndarray | None]  # centre-line coefficients per front model
    track_offsets_m: dict[str, float | None]  # each track's offset at the output's look-ahead
    probabilities: np.ndarray
    selected: int
    output_offset_m: float | None
    output_x_m: float  # the look-ahead of output_offset_m
    output_centre: np.ndarray | None
    reference_m: float | None
    reference_x_m: float  # the look-ahead of reference_m
    reference_repaired: bool
    # The MMAE's residuals r_n (eq. 2): the reference minus each model's offset carried to
    # where the reference looked; NaN where a model was not compared or the MMAE did not run.
    mmae_residuals_m: np.ndarray
    steer: float
    throttle: float
    # The step's truth, computed once by scoring (lanekeep/scoring/step_truth.py): offsets at
    # every look-ahead an estimate reports at or the recorder draws, the centre line, the
    # car's offset after the period. Read by the metrics, the recorder, the plots and tools.
    truth: StepTruth
    pose: tuple[float, float, float]  # after the control period
    sensed_pose: tuple[float, float, float]  # where the frames were taken
    speed_mps: float  # true speed (scoring, recording)
    signals: VehicleSignals  # what the car's sensors said at the frames' time
    events: list[str] = field(default_factory=list)
    tracker_status: dict[str, str] = field(default_factory=dict)  # UpdateStatus value per model
    # Marking masks (uint8, 1 = paint) per camera rendered from the state after this step, the
    # state the next step's frames come from; only when the recorder asks (`wants_masks`).
    marking_masks_after: dict[str, np.ndarray] | None = None
    # Why the car is off the road after this period ("" while on it): `run()` ends there.
    off_road: str = ""
    # Among other vehicles after this period (lanekeep/scoring/safety.py): the vehicle ahead in
    # the car's path, the gap and TTC to it, contact, the car's acceleration, the footprints.
    safety: StepSafety = field(default_factory=StepSafety)
    # Why the car is in contact with another vehicle after this period ("collision with
    # vehicle_3 at t = 12.4 s"; "" while it is not): `run()` ends there.
    collision: str = ""

    @property
    def truth_offset_m(self) -> float:
        """The car's true lateral offset after the period (at `pose`)."""
        return self.truth.car_offset_m

    @property
    def truth_output_m(self) -> float:
        """The true offset at the output's look-ahead, where the frames were taken."""
        return self.truth.offset_at(self.output_x_m)


@dataclass(frozen=True)
class Percept:
    """What the car has at the start of a control period, before it acts: its observation and
    what it made of it. `sensed_pose` (the true pose the frames were taken from) is for
    scoring only."""

    index: int
    observation: Observation
    belief: Belief
    sensed_pose: tuple[float, float, float]

    @property
    def time_s(self) -> float:
        return self.observation.time_s

    @property
    def frames(self):
        return self.observation.frames

    @property
    def signals(self):
        return self.observation.signals

    @property
    def estimates(self):
        return self.belief.estimates

    @property
    def estimate(self):
        return self.belief.estimate

    @property
    def events(self) -> list[str]:
        return self.belief.events
