"""The closed loop's estimator: per-model Kalman tracks, the MMAE and the output policy, one call.

    estimator = LaneEstimator(["hough", "sliding_window"], EstimatorSettings(), 3.7, -4.0)
    out = estimator.update(detections, reference_detection, ego_motion)
    out.centre, out.offset_m  # the lane the controller follows

Per step: each front model's detection becomes a centre line, which updates that model's
tracker (predicted with the ego-motion first; a gated detection that another model
corroborates restarts the track); each track's offset at the look-ahead is carried by
odometry to where the rear reference looks (distance-aligned residuals); the MMAE weighs the
models against the reference; the output is the chosen model's lane. What the estimator is
told of the car's motion comes in `EgoMotion`, never from the simulator directly.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from detectors.base import LaneEstimate, poly_eval
from estimators.alignment import OdometryAlignedHistory
from estimators.consensus import corroborated
from estimators.kalman import LaneTracker, TrackerConfig, UpdateStatus
from estimators.mmae import MMAE, MMAEConfig, MMAEOutput
from lanekeep.config_io import ConfigError, from_dict

ACCEPTED = (UpdateStatus.UPDATED.value, UpdateStatus.INITIALIZED.value,
            UpdateStatus.RESTARTED.value)

TRACKER_TOML = "closed_loop_tracker.toml"


def closed_loop_tracker(text: str | None = None) -> TrackerConfig:
    """The closed loop's tracker tuning from estimators/closed_loop_tracker.toml (or `text`):
    its [tracker] table, with R = r_scale x the measured coefficient covariance."""
    source = TRACKER_TOML
    if text is None:
        text = resources.files("estimators").joinpath(TRACKER_TOML).read_text()
    data = tomllib.loads(text)
    try:
        covariance = np.asarray(data.pop("measured_coefficient_covariance"), dtype=float)
        scale = float(data.pop("r_scale"))
        table = data.pop("tracker")
    except KeyError as err:
        raise ConfigError(source, str(err.args[0]), "required key is missing") from None
    if data:
        raise ConfigError(source, sorted(data)[0], "unknown key")
    if "coefficient_covariance" in table:
        raise ConfigError(source, "tracker.coefficient_covariance",
                          "comes from measured_coefficient_covariance x r_scale")
    table["coefficient_covariance"] = [[scale * v for v in row] for row in covariance.tolist()]
    try:
        return from_dict(TrackerConfig, table, path="tracker", source=source)
    except ConfigError:
        raise
    except ValueError as err:  # TrackerConfig's own checks
        raise ConfigError(source, "tracker", str(err)) from None


CLOSED_LOOP_TRACKER = closed_loop_tracker()


def _no_lap(stage: str) -> None:
    """The default `lap`: no timing."""


@dataclass(frozen=True)
class EgoMotion:
    """What the estimator knows of the car's motion at this step.

    `speed_mps`, `yaw_rate_rps` and `lateral_speed_mps` predict the tracks over `dt_s`;
    `pose` (x, y, yaw in an odometry frame) carries the models' past lane points to where the
    rear reference looks now; `travelled_m` is the odometer.
    """

    dt_s: float
    speed_mps: float
    yaw_rate_rps: float
    lateral_speed_mps: float
    pose: tuple[float, float, float]
    travelled_m: float


@dataclass(frozen=True)
class EstimatorSettings:
    """The scenario's estimation choices the estimator needs (see lanekeep.scenario)."""

    offset_lookahead_m: float = 4.0
    residual_mode: str = "distance_aligned"
    output: str = "select"
    model_lane: str = "track"


@dataclass(frozen=True)
class EstimatorOutput:
    """One step of the estimator: tracks, the MMAE's view, and the lane it hands on."""

    tracked: dict[str, np.ndarray | None]  # centre-line coefficients per front model
    tracker_status: dict[str, str]  # UpdateStatus value per model
    selection: MMAEOutput
    selected: int  # the model whose lane is the output
    centre: np.ndarray | None
    offset_m: float | None
    events: list[str] = field(default_factory=list)


class LaneEstimator:
    """Trackers, distance-aligned MMAE and output policy for a set of front models."""

    def __init__(self, model_names: list[str], settings: EstimatorSettings,
                 lane_width_m: float, reference_x_m: float,
                 tracker: TrackerConfig = CLOSED_LOOP_TRACKER) -> None:
        self.names = list(model_names)
        self.settings = settings
        self.lane_width_m = lane_width_m
        self.reference_x_m = reference_x_m
        self.tracker_config = tracker
        self.trackers = {name: LaneTracker(tracker) for name in self.names}
        # Distance-aligned residuals: each model's past lane estimate is carried by odometry to
        # the point the reference measures now (estimators/alignment.py), so the MMAE compares
        # values for the same road position at the same step (lag 0 in its own terms).
        # The alignment is done here, once: the MMAE compares what it is given ("same_step").
        self.aligned = OdometryAlignedHistory(len(self.names))
        mode = "same_step" if settings.residual_mode == "distance_aligned" else "one_step_delay"
        self.mmae = MMAE(len(self.names), MMAEConfig(residual_mode=mode))

    def reset(self) -> None:
        for tracker in self.trackers.values():
            tracker.reset()
        self.aligned.reset()
        self.mmae.reset()

    def update(self, detections: dict[str, LaneEstimate], reference: LaneEstimate,
               ego: EgoMotion, lap: Callable[[str], None] = _no_lap) -> EstimatorOutput:
        """One control step: the front models' detections and the reference's.

        `lap(stage)` is called after the trackers ("track") and after the MMAE and the output
        ("mmae"), for a caller's stage timing (lanekeep.timing.StageClock.lap).
        """
        events: list[str] = []
        centres = {name: self.centre_of(detections[name]) for name in self.names}
        tracked, status = self._track(centres, ego)
        lap("track")
        selection = self._select(reference, tracked, ego, events)
        selected, centre, offset = self._output(centres, tracked, status, selection)
        lap("mmae")
        return EstimatorOutput(tracked, status, selection, selected, centre, offset, events)

    def centre_of(self, estimate: LaneEstimate) -> np.ndarray | None:
        """Centre line of a detection; one boundary is shifted by half a lane."""
        if not estimate.valid:
            return None
        if estimate.center is not None:
            return estimate.center
        half = self.lane_width_m / 2.0
        if estimate.left is not None:
            return np.asarray(estimate.left) - [half, 0.0, 0.0]
        if estimate.right is not None:
            return np.asarray(estimate.right) + [half, 0.0, 0.0]
        return None

    # -- the stages ----------------------------------------------------------------------------
    def _track(self, centres: dict[str, np.ndarray | None], ego: EgoMotion
               ) -> tuple[dict[str, np.ndarray | None], dict[str, str]]:
        """Predict and update each model's tracker with its detection's centre line. A
        detection the gate rejects but another model's detection corroborates restarts that
        track: the track, not the two detectors, has lost the road (a tight turn's onset
        outruns the constant-rate model)."""
        agreed = dict(zip(centres, corroborated(list(centres.values()),
                                                self.tracker_config.coefficient_r),
                          strict=True))
        tracked, status = {}, {}
        for name, tracker in self.trackers.items():
            tracker.predict(ego.dt_s, ego.speed_mps, ego.yaw_rate_rps, ego.lateral_speed_mps)
            result = tracker.update_coefficients(centres[name])
            if result.status is UpdateStatus.GATED and agreed[name]:
                result = tracker.restart(centres[name])
            status[name] = result.status.value
            tracked[name] = tracker.coefficients
        return tracked, status

    def _select(self, reference: LaneEstimate, tracked, ego: EgoMotion,
                events: list[str]) -> MMAEOutput:
        x_eval = self.settings.offset_lookahead_m
        offsets, variances = [], []
        for tracker in self.trackers.values():
            offsets.append(tracker.offset_m(x_eval))
            variances.append(tracker.offset_variance_m2(x_eval))
        if self.settings.residual_mode == "distance_aligned":
            self.aligned.push(ego.pose, list(tracked.values()), variances, x_eval)
            offsets, variances = self.aligned.offsets_at(ego.pose, self.reference_x_m)
        selection = self.mmae.step(
            reference.offset_m if reference.valid else None,
            offsets,
            variances,
            s_m=ego.travelled_m,
        )
        if selection.reference_repaired:
            events.append(f"reference repaired: {reference.offset_m:+.2f} m -> "
                          f"{selection.reference_m:+.2f} m")
        return selection

    def _output(self, centres, tracked, status, selection
                ) -> tuple[int, np.ndarray | None, float | None]:
        """The lane the controller follows: the MMAE output.

        By default (`model_lane = "track"`) the selected model's Kalman estimate, the state of
        the MMAE bank's likeliest filter: it averages a model's fit noise over steps, which
        the raw detections (the model columns of the report) do not. `model_lane =
        "detection"` is the paper's PID input: the selected model's own detection, with its
        track standing in while the detector has nothing or failed the track's chi-square
        gate (one wild fit, a boundary bent onto a passing car, would otherwise steer the car
        off its lane within a step). "fused" weights each model's lane by its probability.
        """
        names = self.names
        chosen = int(selection.selected)
        lanes = {n: self._lane_of(centres[n], tracked[n], status[n]) for n in names}
        if self.settings.output == "fused":
            polys = [(p, lanes[n]) for p, n in zip(selection.probabilities, names, strict=True)
                     if lanes[n] is not None]
            if not polys:
                return chosen, None, None
            weight = sum(p for p, _ in polys)
            centre = sum(p * c for p, c in polys) / weight
        else:
            chosen = self._choose(selection.probabilities, status)
            centre = lanes[names[chosen]]
            if centre is None:  # the selected model has nothing at all: take any live one
                live = [lanes[n] for n in names if lanes[n] is not None]
                centre = live[0] if live else None
        if centre is None:
            return chosen, None, None
        return chosen, centre, -float(poly_eval(centre, self.settings.offset_lookahead_m))

    def _choose(self, probabilities: np.ndarray, status: dict[str, str]) -> int:
        """The MMAE's likeliest model, unless its filter rejected (or had no) detection this
        step while another's accepted one: then the likeliest of those.

        The probabilities come from the rear reference, which sees a stretch of road only
        after the front models have passed it (distance-aligned residuals lag by ~1 s at
        15 m/s), so they cannot react to a track that starts coasting now. A coasting track
        extrapolates; an updated one has just been checked against its own detection.
        """
        order = np.argsort(-np.asarray(probabilities), kind="stable")
        accepted = [i for i in order if status[self.names[i]] in ACCEPTED]
        if not accepted or order[0] in accepted:
            return int(order[0])
        return int(accepted[0])

    def _lane_of(self, centre: np.ndarray | None, tracked: np.ndarray | None, status: str
                 ) -> np.ndarray | None:
        """The model's track, or ("detection" mode) its detection's centre if the track
        accepted it. Either way a rejected or missing detection leaves the (coasting) track.
        """
        if self.settings.model_lane == "track" and tracked is not None:
            return tracked
        if centre is None or status not in ACCEPTED:
            return tracked
        return np.asarray(centre)
