"""The closed loop's estimator: per-model Kalman tracks, the MMAE and the output policy, one call.

    estimator = LaneEstimator(["hough", "sliding_window"], EstimatorSettings(), -4.0)
    out = estimator.update(detections, reference_detection, ego_motion)
    out.centre, out.offset_m  # the lane the controller follows

Per step: each front model's detection becomes a centre line, which updates that model's
tracker (predicted with the ego-motion first; a gated detection that another model
corroborates restarts the track); each track's offset at the look-ahead is carried by
odometry to where the rear reference looks (distance-aligned residuals); the MMAE weighs the
models against the reference; the output is the chosen model's lane. What the estimator is
told of the car's motion comes in `EgoMotion` (dead-reckoned from the car's sensors,
estimators/odometry.py), never from the simulator; the lane width that centres a one-boundary
detection is measured from the detections themselves.
"""

from __future__ import annotations

import functools
import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from lanekeep.core.config_io import ConfigError, from_dict
from lanekeep.detectors.base import LaneEstimate
from lanekeep.estimators.alignment import OdometryAlignedHistory
from lanekeep.estimators.confidence import ConfidenceBands
from lanekeep.estimators.consensus import corroborated
from lanekeep.estimators.kalman import LaneTracker, TrackerConfig, UpdateStatus
from lanekeep.estimators.mmae import MMAE, MMAEConfig, MMAEOutput
from lanekeep.estimators.odometry import EgoMotion
from lanekeep.estimators.settings import EstimatorSettings
from lanekeep.geometry.lane_poly import LanePoly

ACCEPTED = (UpdateStatus.UPDATED.value, UpdateStatus.INITIALIZED.value,
            UpdateStatus.RESTARTED.value)

TRACKER_TOML = "closed_loop_tracker.toml"
# Paper 001 eq. 8 with its own numbers (§2.3): R = 1e-6 and the final P of model #1 (hough)
# and model #2 (sliding_window), of which C = [1 0] keeps P[0, 0]. The paper gives no unit;
# read as metres (ours) the density's width is 1 mm, read as its tables' cm 10 um: either way
# far below any camera's error. A model the paper does not have takes the larger P[0, 0].
PAPER_R_M2 = 1e-6
PAPER_OFFSET_VARIANCE_M2 = {"hough": 6.25e-13, "sliding_window": 8.14e-13}
BY_DETECTOR = "measured_coefficient_covariance_by_detector"
CONFIDENCE_BY_DETECTOR = "confidence_noise_by_detector"


@dataclass(frozen=True)
class TrackerTuning:
    """The closed loop's trackers: each detector measured on its own gets its own R (the
    learned detector's fits scatter far less than the classical ones', and a track with its
    detector's R neither lags a good detector nor follows a noisy one's scatter); any other
    detector (a plug-in) gets the pooled one, `default`. `confidence_bands`: per detector,
    the factor of R for each band of its detections' confidence (estimators/confidence.py;
    used with `EstimatorSettings.confidence_noise`); a detector without bands gets 1."""

    default: TrackerConfig
    by_detector: Mapping[str, TrackerConfig] = field(default_factory=dict)
    confidence_bands: Mapping[str, ConfidenceBands] = field(default_factory=dict)

    def for_detector(self, name: str) -> TrackerConfig:
        return self.by_detector.get(name, self.default)

    def bands_for(self, name: str) -> ConfidenceBands | None:
        return self.confidence_bands.get(name)


def _covariance(value: object, key: str, source: str) -> np.ndarray:
    """A measured 3x3 coefficient covariance from the tuning file."""
    try:
        matrix = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        matrix = np.empty(0)
    if matrix.shape != (3, 3):
        raise ConfigError(source, key, "must be a 3x3 matrix of numbers")
    return matrix


def closed_loop_tracker(text: str | None = None) -> TrackerTuning:
    """The closed loop's tracker tuning from estimators/closed_loop_tracker.toml (or `text`):
    its [tracker] table, with R = r_scale x the measured coefficient covariance, the pooled
    one (`measured_coefficient_covariance`) as the default and each detector's own
    (`[measured_coefficient_covariance_by_detector]`) for that detector."""
    source = TRACKER_TOML
    if text is None:
        text = resources.files("lanekeep.estimators").joinpath(TRACKER_TOML).read_text()
    data = tomllib.loads(text)
    try:
        pooled = _covariance(data.pop("measured_coefficient_covariance"),
                             "measured_coefficient_covariance", source)
        per_detector = data.pop(BY_DETECTOR, {})
        confidence = data.pop(CONFIDENCE_BY_DETECTOR, {})
        scale = float(data.pop("r_scale"))
        table = data.pop("tracker")
    except KeyError as err:
        raise ConfigError(source, str(err.args[0]), "required key is missing") from None
    if data:
        raise ConfigError(source, sorted(data)[0], "unknown key")
    if "coefficient_covariance" in table:
        raise ConfigError(source, "tracker.coefficient_covariance",
                          "comes from measured_coefficient_covariance x r_scale")

    def config(covariance: np.ndarray, key: str) -> TrackerConfig:
        rows = [[scale * v for v in row] for row in covariance.tolist()]
        try:
            return from_dict(TrackerConfig, {**table, "coefficient_covariance": rows},
                             path="tracker", source=source)
        except ConfigError:
            raise
        except ValueError as err:  # TrackerConfig's own checks
            raise ConfigError(source, key, str(err)) from None

    if not isinstance(per_detector, dict):
        raise ConfigError(source, BY_DETECTOR, "must be a table of detector = 3x3 matrix")
    by_detector = {name: config(_covariance(value, f"{BY_DETECTOR}.{name}", source),
                                f"{BY_DETECTOR}.{name}")
                   for name, value in per_detector.items()}
    return TrackerTuning(config(pooled, "tracker"), by_detector,
                         _confidence_bands(confidence, source))


def _confidence_bands(table: object, source: str) -> dict[str, ConfidenceBands]:
    """`[confidence_noise_by_detector]`: per detector `{ edges = [...], scales = [...] }`."""
    if not isinstance(table, dict):
        raise ConfigError(source, CONFIDENCE_BY_DETECTOR,
                          "must be a table of detector = { edges = [...], scales = [...] }")
    bands = {}
    for name, value in table.items():
        key = f"{CONFIDENCE_BY_DETECTOR}.{name}"
        if not isinstance(value, dict) or set(value) != {"edges", "scales"}:
            raise ConfigError(source, key, "must be { edges = [...], scales = [...] }")
        try:
            bands[name] = ConfidenceBands(tuple(float(v) for v in value["edges"]),
                                          tuple(float(v) for v in value["scales"]))
        except (TypeError, ValueError) as err:
            raise ConfigError(source, key, str(err)) from None
    return bands


@functools.cache
def shipped_tracker() -> TrackerTuning:
    """The shipped tuning (estimators/closed_loop_tracker.toml), read once, on first use (not
    at import: importing the estimator reads no file)."""
    return closed_loop_tracker()


def _no_lap(stage: str) -> None:
    """The default `lap`: no timing."""


@dataclass(frozen=True)
class EstimatorOutput:
    """One step of the estimator: tracks, the MMAE's view, and the lane it hands on."""

    tracked: dict[str, np.ndarray | None]  # centre-line coefficients per front model
    tracker_status: dict[str, str]  # UpdateStatus value per model
    selection: MMAEOutput
    selected: int  # the model whose lane is the output
    centre: np.ndarray | None
    offset_m: float | None
    offset_x_m: float  # the look-ahead `offset_m` refers to
    reference_x_m: float  # the look-ahead of `selection.reference_m`
    events: list[str] = field(default_factory=list)


class LaneEstimator:
    """Trackers, distance-aligned MMAE and output policy for a set of front models."""

    def __init__(self, model_names: list[str], settings: EstimatorSettings,
                 reference_x_m: float,
                 tracker: TrackerConfig | TrackerTuning | None = None,
                 families: Mapping[str, str] | None = None) -> None:
        """`families`: per model, the detector whose measured noise its tracker takes (a
        plug-in that subclasses a built-in: the built-in's name); a model not in it, its own."""
        self.names = list(model_names)
        families = families or {}
        self.settings = settings
        self.lane_width_m = settings.lane_width_prior_m
        self.reference_x_m = reference_x_m
        if tracker is None:  # the closed loop's own: what an Episode runs
            tracker = shipped_tracker()
        tuning = tracker if isinstance(tracker, TrackerTuning) else TrackerTuning(tracker)
        self.tracker_configs = {name: tuning.for_detector(families.get(name, name))
                                for name in self.names}
        self.confidence_bands = ({name: tuning.bands_for(families.get(name, name))
                                  for name in self.names} if settings.confidence_noise else {})
        self.trackers = {name: LaneTracker(self.tracker_configs[name]) for name in self.names}
        # Distance-aligned residuals: each model's past lane estimate is carried by odometry to
        # the point the reference measures now (estimators/alignment.py), so the MMAE compares
        # values for the same road position at the same step (lag 0 in its own terms).
        # The alignment is done here, once: the MMAE compares what it is given ("same_step").
        self.aligned = OdometryAlignedHistory(len(self.names))
        mode = "same_step" if settings.residual_mode == "distance_aligned" else "one_step_delay"
        paper_psi = settings.residual_covariance == "paper"
        self._paper_variances = [
            PAPER_OFFSET_VARIANCE_M2.get(families.get(n, n), max(PAPER_OFFSET_VARIANCE_M2.values()))
            for n in self.names] if paper_psi else None
        reference_std = float(np.sqrt(PAPER_R_M2)) if paper_psi else settings.reference_std_m
        self.mmae = MMAE(len(self.names),
                         MMAEConfig(residual_mode=mode, reference_std_m=reference_std,
                                    probability_floor=settings.probability_floor),
                         prior=self._prior(settings))
        # missing_model = "hold": each model's last valid detection, standing in while it has
        # none (the paper's loop has a value for every model at every step).
        self._held: dict[str, LaneEstimate] = {}

    def _prior(self, settings: EstimatorSettings) -> np.ndarray | None:
        """The MMAE's starting probabilities (`EstimatorSettings.mmae_prior`)."""
        if settings.mmae_prior == "uniform":
            return None
        x = settings.offset_lookahead_m
        c = np.array([1.0, x, x * x])
        return np.array([1.0 / float(c @ self.tracker_configs[n].coefficient_r @ c)
                         for n in self.names])

    def reset(self) -> None:
        self.lane_width_m = self.settings.lane_width_prior_m
        for tracker in self.trackers.values():
            tracker.reset()
        self.aligned.reset()
        self.mmae.reset()
        self._held.clear()

    def update(self, detections: dict[str, LaneEstimate], reference: LaneEstimate,
               ego: EgoMotion, lap: Callable[[str], None] = _no_lap) -> EstimatorOutput:
        """One control step: the front models' detections and the reference's.

        `lap(stage)` is called after the trackers ("track") and after the MMAE and the output
        ("mmae"), for a caller's stage timing (lanekeep.core.timing.StageClock.lap).
        """
        events: list[str] = []
        self._hold(detections)
        self._measure_lane_width(detections.values())
        centres = {name: self.centre_of(detections[name]) for name in self.names}
        reference_centre = self._usable_reference(reference)
        scales = {name: self._r_scale(name, detections[name]) for name in self.names}
        tracked, status = self._track(centres, scales, ego, reference_centre, events)
        lap("track")
        selection, reference_x = self._select(reference, tracked, detections, ego, events)
        selected, centre = self._output(centres, tracked, status, selection)
        if centre is None and reference_centre is not None and self.settings.reference_fallback:
            centre = reference_centre
            events.append("no front lane: the output is the rear reference's")
        offset, x_m = self._offset(selected, centre, detections, tracked, status)
        lap("mmae")
        return EstimatorOutput(tracked, status, selection, selected, centre, offset, x_m,
                               reference_x, events)

    def _carried(self, name: str, detection: LaneEstimate) -> LaneEstimate:
        """The detection a model hands the MMAE and the paper's PID input: its own, or with
        `missing_model = "hold"` its last valid one while it has none (the paper's loop
        carries a value for every model at every step). The trackers see only real ones."""
        if self.settings.missing_model != "hold" or detection.valid:
            return detection
        return self._held.get(name, detection)

    def _hold(self, detections: dict[str, LaneEstimate]) -> None:
        """With `missing_model = "hold"`: remember each model's latest valid detection."""
        if self.settings.missing_model == "hold":
            self._held.update({n: d for n, d in detections.items() if d.valid})

    def _measure_lane_width(self, detections) -> None:
        """Update the running lane width from this step's two-boundary detections."""
        x = self.settings.offset_lookahead_m
        lo, hi = self.settings.lane_width_range_m
        gain = self.settings.lane_width_gain
        for estimate in detections:
            width = self._pair_width(estimate, x)
            if width is not None and lo <= width <= hi:
                self.lane_width_m += gain * (width - self.lane_width_m)

    def centre_of(self, estimate: LaneEstimate) -> np.ndarray | None:
        """Centre line of a detection; one boundary is shifted by half the measured lane
        width."""
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
    def _r_scale(self, name: str, detection: LaneEstimate) -> float:
        """The factor of the model's R for this detection: its confidence band's with
        `confidence_noise` (estimators/confidence.py), else 1."""
        bands = self.confidence_bands.get(name)
        if bands is None or not detection.valid:
            return 1.0
        return bands.scale(detection.confidence)

    def _track(self, centres: dict[str, np.ndarray | None], scales: dict[str, float],
               ego: EgoMotion, reference: np.ndarray | None, events: list[str]
               ) -> tuple[dict[str, np.ndarray | None], dict[str, str]]:
        """Predict and update each model's tracker with its detection's centre line. A
        detection the gate rejects but another model's detection corroborates restarts that
        track: the track, not the two detectors, has lost the road (a tight turn's onset
        outruns the constant-rate model). A track starts or restarts only from a lane that
        meets the rear reference's at the car (`_meets_reference`); with
        `track_reference_check = "updates"` every detection a track takes must."""
        noise = [scales[name] * self.tracker_configs[name].coefficient_r for name in centres]
        agreed = dict(zip(centres, corroborated(list(centres.values()), noise), strict=True))
        tracked, status = {}, {}
        every_update = self.settings.track_reference_check == "updates"
        for name, tracker in self.trackers.items():
            tracker.predict(ego.dt_s, ego.speed_mps, ego.yaw_rate_rps, ego.lateral_speed_mps)
            centre = centres[name]
            meets = self._meets_reference(centre, reference)
            if centre is not None and not meets and (not tracker.valid or every_update):
                what = "update" if tracker.valid else "start"
                heading = ("" if self.settings.track_start_gate_heading_rad is None else
                           f" and {self._heading_gap(centre, reference):.3f} rad")
                events.append(f"{name}: track {what} refused: its lane "
                              f"{self._gap_at_car(centre, reference):.2f} m{heading} from the "
                              f"reference's at the car")
                centre = None  # a miss: the track waits for a lane the reference confirms
            result = tracker.update_coefficients(centre, scales[name])
            if result.status is UpdateStatus.GATED and agreed[name] and meets:
                result = tracker.restart(centre, scales[name])
            status[name] = result.status.value
            tracked[name] = tracker.coefficients
        return tracked, status

    def _usable_reference(self, reference: LaneEstimate) -> np.ndarray | None:
        """The rear reference's centre line where it can stand for the car's lane (a front
        track's start, the fallback output): valid and, with the width check on, as wide as
        the lane measured in front."""
        centre = self.centre_of(reference)
        if centre is None:
            return None
        width = self._pair_width(reference, 0.0)
        tolerance = self.settings.reference_width_tolerance_m
        if width is not None and tolerance is not None \
                and abs(width - self.lane_width_m) > tolerance:
            return None
        return centre

    @staticmethod
    def _gap_at_car(centre: np.ndarray, reference: np.ndarray) -> float:
        """How far apart two centre lines are at the car (x = 0), m."""
        return abs(float(centre[0]) - float(reference[0]))

    def _meets_reference(self, centre: np.ndarray | None, reference: np.ndarray | None) -> bool:
        """Whether a front lane may start a track: no reference to ask, or the two meet at
        the car within `track_start_gate_lane_widths` of the measured lane width (and, with
        `track_start_gate_heading_rad`, run within that heading of each other there)."""
        gate = self.settings.track_start_gate_lane_widths
        if centre is None or reference is None or gate is None:
            return True
        heading = self.settings.track_start_gate_heading_rad
        if heading is not None and self._heading_gap(centre, reference) > heading:
            return False
        return self._gap_at_car(centre, reference) <= gate * self.lane_width_m

    @staticmethod
    def _heading_gap(centre: np.ndarray, reference: np.ndarray) -> float:
        """How far apart two centre lines' headings are at the car (x = 0), rad."""
        return abs(math.atan(float(centre[1])) - math.atan(float(reference[1])))

    def _select(self, reference: LaneEstimate, tracked, detections: dict[str, LaneEstimate],
                ego: EgoMotion, events: list[str]) -> tuple[MMAEOutput, float]:
        """The MMAE step, and the look-ahead of the reference offset it compared."""
        x_eval = self.settings.offset_lookahead_m
        at_car = self.settings.mmae_input == "detection" and self.settings.mmae_at_car
        offsets, variances = [], []
        for name, tracker in self.trackers.items():
            if self.settings.mmae_input == "detection":
                detection = self._carried(name, detections[name])
                x_m = 0.0 if at_car else detection.x_m
                offsets.append(self._offset_of(detection, x_m))
                variances.append(tracker.offset_variance_m2(x_m))
            else:
                offsets.append(tracker.offset_m(x_eval))
                variances.append(tracker.offset_variance_m2(x_eval))
        if self._paper_variances is not None:  # eq. 8 with the paper's P
            variances = [v if o is not None else None
                         for o, v in zip(offsets, self._paper_variances, strict=True)]
        if self.settings.residual_mode == "distance_aligned":
            self.aligned.push(ego.pose, list(tracked.values()), variances, x_eval)
            offsets, variances = self.aligned.offsets_at(ego.pose, self.reference_x_m)
        reference_x = 0.0 if at_car else float(reference.x_m)
        reference_m = self._offset_of(reference, reference_x)
        width = self._pair_width(reference, reference_x)
        tolerance = self.settings.reference_width_tolerance_m
        if reference_m is not None and width is not None and tolerance is not None \
                and abs(width - self.lane_width_m) > tolerance:
            events.append(f"reference ignored: its lane {width:.2f} m wide against "
                          f"{self.lane_width_m:.2f} m measured in front")
            reference_m = None  # a missed reference: the probabilities stay as they are
        selection = self.mmae.step(reference_m, offsets, variances, s_m=ego.travelled_m)
        if selection.reference_repaired and reference_m is not None:
            events.append(f"reference repaired: {reference_m:+.2f} m -> "
                          f"{selection.reference_m:+.2f} m")
        return selection, reference_x

    @staticmethod
    def _pair_width(detection: LaneEstimate, x_m: float) -> float | None:
        """The width between a detection's two boundaries at x, None without both."""
        if not detection.valid or detection.left is None or detection.right is None:
            return None
        return float(LanePoly.of(detection.left).y(x_m) - LanePoly.of(detection.right).y(x_m))

    def _offset_of(self, detection: LaneEstimate, x_m: float) -> float | None:
        """A detection's offset at x: its own where it reports it, else from its centre line."""
        if not detection.valid:
            return None
        if abs(x_m - detection.x_m) < 1e-9:
            return float(detection.offset_m)
        centre = self.centre_of(detection)
        return None if centre is None else float(LanePoly.of(centre).offset_m(x_m))

    def _output(self, centres, tracked, status, selection
                ) -> tuple[int, np.ndarray | None]:
        """The lane the controller follows: the MMAE output.

        By default (`model_lane = "track"`) the selected model's Kalman estimate, the state of
        the MMAE bank's likeliest filter: it averages a model's fit noise over steps, which
        the raw detections (the model columns of the report) do not. `model_lane =
        "detection"` is the paper's PID input: the selected model's own detection, with its
        track standing in while the detector has nothing or failed the track's chi-square
        gate (one wild fit, a boundary bent onto a passing car, would otherwise steer the car
        off its lane within a step). "fused" weights each model's lane by its probability;
        "precision" fuses the lanes with their tracks' covariances (`_precision_fused`).
        """
        names = self.names
        chosen = int(selection.selected)
        lanes = {n: self._lane_of(centres[n], tracked[n], status[n]) for n in names}
        live = [i for i, n in enumerate(names) if lanes[n] is not None]
        if self.settings.output in ("fused", "precision"):
            if not live:
                return chosen, None
            p = selection.probabilities
            centre = None
            if self.settings.output == "precision":
                centre = self._precision_fused(lanes, p)
            if centre is None:  # probability-weighted (or no live track has a covariance)
                centre = sum(p[i] * lanes[names[i]] for i in live) / sum(p[i] for i in live)
        else:
            chosen = self._choose(selection.probabilities, status)
            centre = lanes[names[chosen]]
            if centre is None:  # the selected model has nothing at all: take any live one
                centre = lanes[names[live[0]]] if live else None
        return chosen, centre

    def _offset(self, selected: int, centre: np.ndarray | None,
                detections: dict[str, LaneEstimate], tracked, status
                ) -> tuple[float | None, float]:
        """The output offset and the look-ahead it is at (see `EstimatorSettings.output_at`)."""
        x_m = self.settings.offset_lookahead_m
        if self.settings.output_at == "nearest_row":
            name = self.names[selected]
            detection = self._carried(name, detections[name])
            x_m = float(detection.x_m)
            if detection.valid:  # the paper's PID reads the detection, gate or not
                return float(detection.offset_m), x_m
            centre = tracked[name] if tracked[name] is not None else centre
        if centre is None:
            return None, x_m
        return float(LanePoly.of(centre).offset_m(x_m)), x_m

    def _precision_fused(self, lanes: dict[str, np.ndarray | None],
                         probabilities: np.ndarray) -> np.ndarray | None:
        """The product of the models' Gaussians: c = (sum_n p_n P_n^-1)^-1 sum_n p_n P_n^-1 c_n.

        Each model's lane is a Gaussian estimate of the road's [c0, c1, c2] with its track's
        covariance P_n (which its detector's measured R and its own history set, and which
        grows while it coasts), made wider by 1 / p_n for a model the MMAE trusts less. Each
        coefficient then comes from the models that measure it well: the near offset from a
        steady model, the far curvature from one whose fits hold out there (lanenet's near
        offset is the steadiest and its far curvature the noisiest, closed_loop_tracker.toml),
        and models that are alike average. None when no live lane has a track.
        """
        information = np.zeros((3, 3))
        vector = np.zeros(3)
        for p, name in zip(probabilities, self.names, strict=True):
            covariance = self.trackers[name].coefficient_covariance
            if lanes[name] is None or covariance is None:
                continue
            weight = p * np.linalg.inv(covariance)  # p_n P_n^-1
            information += weight
            vector += weight @ np.asarray(lanes[name], dtype=float)
        if not information.any():
            return None
        return np.linalg.solve(information, vector)

    def _choose(self, probabilities: np.ndarray, status: dict[str, str]) -> int:
        """The MMAE's likeliest model, unless its filter rejected (or had no) detection this
        step while another's accepted one: then the likeliest of those.

        The probabilities come from the rear reference, which sees a stretch of road only
        after the front models have passed it (distance-aligned residuals lag by ~1 s at
        15 m/s), so they cannot react to a track that starts coasting now. A coasting track
        extrapolates; an updated one has just been checked against its own detection.
        """
        order = np.argsort(-np.asarray(probabilities), kind="stable")
        if not self.settings.prefer_accepted:
            return int(order[0])
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
