"""One closed-loop episode: sense, detect, track, select, control, actuate, score, record.

Each line of `Episode.step` is one call into one module (DESIGN.md's loop). The front
detectors each feed a Kalman lane tracker; the rear detector is the MMAE's reference (the
paper's "observer"); the MMAE selects (or fuses) the front models; the PID steers on the chosen
lane's offset at the control look-ahead; the speed PI holds the target speed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from detectors.base import Detector, LaneEstimate, poly_eval
from detectors.registry import make_detector
from estimators.alignment import OdometryAlignedHistory
from estimators.consensus import corroborated
from estimators.kalman import LaneTracker, TrackerConfig, UpdateStatus
from estimators.mmae import MMAE, MMAEConfig
from lanekeep import world_conditions
from lanekeep.cameras import CameraRig, RenderSettings
from lanekeep.conditions import ImageEffects
from lanekeep.control import SpeedController, SteeringPID
from lanekeep.ground_truth import lane_offsets, lane_truth
from lanekeep.metrics import EpisodeReport, Metrics
from lanekeep.record import NullRecorder, Recorder
from lanekeep.scenario import Scenario
from lanekeep.timing import StageClock
from lanekeep.world import World, build, physics_steps_per_control

FUSED, REFERENCE = "fused", "reference"
TYRES = ("front_left_tyre", "front_right_tyre", "rear_left_tyre", "rear_right_tyre")
_ACCEPTED = (UpdateStatus.UPDATED.value, UpdateStatus.INITIALIZED.value,
             UpdateStatus.RESTARTED.value)

# Tracker noise for the closed loop. Ego-motion explains most of the lane's motion in the car
# frame; what it cannot is the road's own curvature change (a clothoid into a 40 m radius turns
# c2 by 0.0125 /m within 1.3 s at 15 m/s, a rate of ~0.01 /m/s) and the sideslip change that
# comes with it (c1 ~0.03 /s). Q is sized so the filter follows those within 2-3 steps
# instead of gating the detector as an outlier.
#
# R is the covariance of both detectors' centre-line coefficient errors measured in the loop
# (`python tools/measure_detector_noise.py`: clear_straight, clear_curve, paper cases 2 and 3,
# 1,900 detections, the 80% core of a robust fit; stds 5.6 cm, 0.0098, 4.4e-4 /m) with its
# standard deviations doubled (x4): the core holds only 80% of the detections, and fits in
# tight turns, shade and rain are worse than the average.
MEASURED_COEFFICIENT_COVARIANCE = (
    (3.18e-3, -5.05e-4, 2.21e-5),
    (-5.05e-4, 9.57e-5, -4.28e-6),
    (2.21e-5, -4.28e-6, 1.94e-7),
)
CLOSED_LOOP_TRACKER = TrackerConfig(
    c1_accel_psd_ps3=1e-3, c2_accel_psd_pm2ps3=3e-4,
    # With the ego-motion predicted, a lane's coefficients hardly drift on their own: a new
    # track's rates start near 0 (0.1 m/s, 0.02 /s), not free. A free c0 rate (1 m/s) takes
    # the first innovation after a (re)start, one fit's noise over one step, for a drift and
    # coasts the track off the road.
    initial_rate_std=(0.1, 0.02, 1e-3),
    # A coasting track moves with the ego-motion only: in snow one accepted bad fit gave the
    # c2 rate 0.024 /s (2.5x the sharpest clothoid we ship), and the car, steered by the
    # coasting track, followed a 40 m hairpin off a 300 m curve.
    coast_with_rates=False,
    coefficient_covariance=tuple(tuple(4.0 * v for v in row)
                                 for row in MEASURED_COEFFICIENT_COVARIANCE),
)


@dataclass(frozen=True)
class StepResult:
    """Everything one control step produced (what the recorder and the dm_env wrapper see)."""

    index: int
    time_s: float
    frames: dict[str, np.ndarray]
    estimates: dict[str, LaneEstimate]
    tracked: dict[str, np.ndarray | None]  # centre-line coefficients per front model
    probabilities: np.ndarray
    selected: int
    output_offset_m: float | None
    output_centre: np.ndarray | None
    reference_m: float | None
    reference_repaired: bool
    steer: float
    throttle: float
    truth_offset_m: float  # the car's true lateral offset after the period (at `pose`)
    truth_centre: np.ndarray  # true lane centre in the frame of `sensed_pose`
    pose: tuple[float, float, float]  # after the control period
    sensed_pose: tuple[float, float, float]  # where the frames were taken
    speed_mps: float
    events: list[str] = field(default_factory=list)
    tracker_status: dict[str, str] = field(default_factory=dict)  # UpdateStatus value per model


class Episode:
    """A closed-loop run of one scenario; `run()` steps it to the end and returns the report."""

    def __init__(self, scenario: Scenario, recorder: Recorder | None = None,
                 render_size: tuple[int, int] | None = None) -> None:
        self.scenario = scenario
        est = scenario.estimation
        self.world: World = build(scenario)
        width, height = render_size or (scenario.camera.width, scenario.camera.height)
        self.rig = CameraRig(self.world.model,
                             RenderSettings(width, height, scenario.camera.shadows))
        self.rng = np.random.default_rng(scenario.seed)
        # One effects pipeline per camera: lens drops persist and slide between frames.
        self.effects = {name: ImageEffects(scenario.conditions, height, width, self.rng)
                        for name in self.rig.CAMERA_NAMES}
        self.dt_s = scenario.control_period_s
        self.substeps = physics_steps_per_control(self.world)
        self.front: dict[str, Detector] = {
            name: make_detector(name, self.rig.cameras["front"]) for name in est.front_detectors
        }
        self.trackers = {name: LaneTracker(CLOSED_LOOP_TRACKER) for name in self.front}
        self.reference: Detector = make_detector(est.reference_detector,
                                                   self.rig.cameras[est.reference_camera])
        # Distance-aligned residuals: each model's past lane estimate is carried by odometry to
        # the point the reference measures now (estimators/alignment.py), so the MMAE compares
        # values for the same road position at the same step (lag 0 in its own terms).
        self.reference_x_m = float(getattr(self.reference, "x_ref", -4.0))
        self.aligned = OdometryAlignedHistory(len(self.front))
        self.travelled_m = 0.0
        self.mmae = MMAE(len(self.front), MMAEConfig(residual_mode=est.residual_mode))
        geometry = self.world.car.geometry
        self.steering = SteeringPID(self.dt_s, est.control_lookahead_m, geometry.wheelbase_m,
                                    geometry.max_steer_rad)
        self.speed = SpeedController(scenario.target_speed_mps, self.dt_s)
        self.metrics = Metrics(list(self.front) + [FUSED, REFERENCE])
        self.recorder: Recorder = recorder or NullRecorder()
        for detector in [*self.front.values(), self.reference]:
            detector.reset()
        self.index = 0
        self.detector_errors = 0
        self.clock = StageClock()  # wall time per stage (`lanekeep perf`)
        self._tyre_geoms = [self.world.model.geom(n).id for n in TYRES]
        self._wall_start = time.perf_counter()

    # -- the loop ------------------------------------------------------------------------------
    def step(self, action: tuple[float, float] | None = None) -> StepResult:
        """One control period. `action` = (steer, throttle) overrides the controllers."""
        clock = self.clock
        clock.start()
        events: list[str] = []
        sensed_pose = self.world.car.pose()  # the pose the frames are taken from
        frames = self._sense()
        estimates = self._detect(frames, events)
        tracked = self._track(estimates)
        clock.lap("track")
        selection = self._select(estimates, tracked, events)
        clock.lap("mmae")
        centre, offset = self._output(estimates, tracked, selection)
        steer, throttle = self._control(centre, offset) if action is None else action
        clock.lap("control")
        self._actuate(steer, throttle)
        clock.lap("physics")
        result = self._score(sensed_pose, frames, estimates, tracked, selection, centre,
                             offset, steer, throttle, events)
        clock.lap("score")
        self.recorder.log_step(self, result)
        clock.lap("record")
        self.index += 1
        return result

    def _sense(self) -> dict[str, np.ndarray]:
        data = self.world.data
        frames = {}
        for name in self.rig.CAMERA_NAMES:
            rgb = self.rig.render_rgb(data, name)
            self.clock.lap(f"render_{name}")
            frames[name] = self.effects[name](rgb, self.rng, speed_mps=self.world.car.speed_mps())
            self.clock.lap(f"effects_{name}")
        return frames

    def _safe_detect(self, name: str, detector: Detector, frame: np.ndarray,
                     events: list[str]) -> LaneEstimate:
        """A detector that raises or returns garbage counts as a miss, with an event."""
        try:
            estimate = detector.detect(frame)
        except (ValueError, FloatingPointError, ArithmeticError) as err:
            self.detector_errors += 1
            events.append(f"detector {name} failed: {err}")
            return LaneEstimate.invalid(f"error: {err}")
        if not isinstance(estimate, LaneEstimate):
            self.detector_errors += 1
            events.append(f"detector {name} returned {type(estimate).__name__}")
            return LaneEstimate.invalid("not a LaneEstimate")
        return estimate

    def _detect(self, frames, events) -> dict[str, LaneEstimate]:
        est = self.scenario.estimation
        out = {}
        for name, detector in self.front.items():
            out[name] = self._safe_detect(name, detector, frames["front"], events)
            self.clock.lap(f"detect_{name}")
        out[REFERENCE] = self._safe_detect(REFERENCE, self.reference,
                                           frames[est.reference_camera], events)
        self.clock.lap("detect_reference")
        return out

    def _track(self, estimates) -> dict[str, np.ndarray | None]:
        """Predict and update each model's tracker. A detection the gate rejects but another
        model's detection corroborates restarts that track: the track, not the two detectors,
        has lost the road (a tight turn's onset outruns the constant-rate model)."""
        car = self.world.car
        centres = {name: self._centre_of(estimates[name]) for name in self.trackers}
        agreed = dict(zip(centres, corroborated(list(centres.values()),
                                                CLOSED_LOOP_TRACKER.coefficient_r), strict=True))
        tracked = {}
        self._tracker_status = {}
        for name, tracker in self.trackers.items():
            tracker.predict(self.dt_s, car.speed_mps(), car.yaw_rate_rps(),
                            car.lateral_speed_mps())
            result = tracker.update_coefficients(centres[name])
            if result.status is UpdateStatus.GATED and agreed[name]:
                result = tracker.restart(centres[name])
            self._tracker_status[name] = result.status.value
            tracked[name] = tracker.coefficients
        return tracked

    def _select(self, estimates, tracked, events):
        x_eval = self.scenario.estimation.offset_lookahead_m
        offsets, variances = [], []
        for tracker in self.trackers.values():
            offsets.append(tracker.offset_m(x_eval))
            variances.append(tracker.offset_variance_m2(x_eval))
        reference = estimates[REFERENCE]
        pose = self.world.car.pose()
        self.travelled_m += abs(self.world.car.speed_mps()) * self.dt_s  # odometry
        if self.scenario.estimation.residual_mode == "distance_aligned":
            self.aligned.push(pose, list(tracked.values()), variances, x_eval)
            offsets, variances = self.aligned.offsets_at(pose, self.reference_x_m)
        selection = self.mmae.step(
            reference.offset_m if reference.valid else None,
            offsets,
            variances,
            s_m=self.travelled_m,
        )
        if selection.reference_repaired:
            events.append(f"reference repaired: {reference.offset_m:+.2f} m -> "
                          f"{selection.reference_m:+.2f} m")
        return selection

    def _output(self, estimates, tracked, selection
                ) -> tuple[np.ndarray | None, float | None]:
        """The lane the controller follows: the MMAE output.

        By default (`model_lane = "track"`) the selected model's Kalman estimate, the state of
        the MMAE bank's likeliest filter: it averages a model's fit noise over steps, which
        the raw detections (the model columns of the report) do not. `model_lane =
        "detection"` is the paper's PID input: the selected model's own detection, with its
        track standing in while the detector has nothing or failed the track's chi-square
        gate (one wild fit, a boundary bent onto a passing car, would otherwise steer the car
        off its lane within a step). "fused" weights each model's lane by its probability.
        """
        names = list(self.trackers)
        self._chosen = int(selection.selected)
        lanes = {n: self._lane_of(estimates[n], tracked[n], self._tracker_status[n])
                 for n in names}
        if self.scenario.estimation.output == "fused":
            polys = [(p, lanes[n]) for p, n in zip(selection.probabilities, names, strict=True)
                     if lanes[n] is not None]
            if not polys:
                return None, None
            weight = sum(p for p, _ in polys)
            centre = sum(p * c for p, c in polys) / weight
        else:
            self._chosen = self._choose(selection.probabilities, names)
            centre = lanes[names[self._chosen]]
            if centre is None:  # the selected model has nothing at all: take any live one
                live = [lanes[n] for n in names if lanes[n] is not None]
                centre = live[0] if live else None
        if centre is None:
            return None, None
        return centre, -float(poly_eval(centre, self.scenario.estimation.offset_lookahead_m))

    def _choose(self, probabilities: np.ndarray, names: list[str]) -> int:
        """The MMAE's likeliest model, unless its filter rejected (or had no) detection this
        step while another's accepted one: then the likeliest of those.

        The probabilities come from the rear reference, which sees a stretch of road only
        after the front models have passed it (distance-aligned residuals lag by ~1 s at
        15 m/s), so they cannot react to a track that starts coasting now. A coasting track
        extrapolates; an updated one has just been checked against its own detection.
        """
        order = np.argsort(-np.asarray(probabilities), kind="stable")
        accepted = [i for i in order if self._tracker_status[names[i]] in _ACCEPTED]
        if not accepted or order[0] in accepted:
            return int(order[0])
        return int(accepted[0])

    def _lane_of(self, estimate: LaneEstimate, tracked: np.ndarray | None, status: str
                 ) -> np.ndarray | None:
        """The model's track, or ("detection" mode) its detection if the track accepted it.

        Either way a rejected or missing detection leaves the (coasting) track.
        """
        centre = self._centre_of(estimate)
        if self.scenario.estimation.model_lane == "track" and tracked is not None:
            return tracked
        if centre is None or status not in _ACCEPTED:
            return tracked
        return np.asarray(centre)

    def _centre_of(self, estimate: LaneEstimate) -> np.ndarray | None:
        """Centre line of a detection; one boundary is shifted by half a lane."""
        if not estimate.valid:
            return None
        if estimate.center is not None:
            return estimate.center
        half = self.world.road.lane_width_m / 2.0
        if estimate.left is not None:
            return np.asarray(estimate.left) - [half, 0.0, 0.0]
        if estimate.right is not None:
            return np.asarray(estimate.right) + [half, 0.0, 0.0]
        return None

    def _control(self, centre, offset) -> tuple[float, float]:
        car = self.world.car
        if centre is None:
            steer = self.steering(None, car.speed_mps())
        else:
            # Feedback on the lane's offset and heading projected x_ctrl ahead (the linear
            # terms); its curvature goes to the controller's feed-forward, not counted twice.
            x_ctrl = self.scenario.estimation.control_lookahead_m
            control_offset = -float(centre[0] + centre[1] * x_ctrl)
            # Curvature of the lane where the controller looks: 2 c2 / (1 + y'^2)^1.5. A
            # quadratic fitted to a tight arc over 4-20 m inflates c2 (it absorbs the arc's x^4
            # term), and 2 c2 alone would over-steer a 40 m radius turn by ~25%.
            slope = centre[1] + 2.0 * centre[2] * x_ctrl
            curvature = 2.0 * centre[2] / (1.0 + slope * slope) ** 1.5
            steer = self.steering(control_offset, car.speed_mps(), curvature_1pm=curvature)
        return steer, self.speed(car.speed_mps())

    def _actuate(self, steer: float, throttle: float) -> None:
        self.world.car.apply(steer, throttle)
        model, data = self.world.model, self.world.data
        for _ in range(self.substeps):
            mujoco.mj_step(model, data)
        world_conditions.update_dynamic(self.world, data.time)

    def _score(self, sensed_pose, frames, estimates, tracked, selection, centre, offset, steer,
               throttle, events) -> StepResult:
        """Estimates against the truth of the pose their frames were taken from; the car's own
        lateral error and lane departures at its pose after the control period."""
        world, est = self.world, self.scenario.estimation
        lane = self.scenario.road.ego_lane
        # One truth of the lane where the frames were taken, and its offsets at every
        # look-ahead that an estimate reports at (one Newton solve for all of them).
        sensed = lane_truth(world.road, *sensed_pose, lane)
        lookaheads = sorted({round(e.x_m, 3) for e in estimates.values()}
                            | {round(est.offset_lookahead_m, 3)})
        offsets = dict(zip(lookaheads, lane_offsets(world.road, *sensed_pose, lane, lookaheads,
                                                    s_car=sensed.s_m), strict=True))

        def true_offset(x_m: float) -> float:
            return float(offsets[round(x_m, 3)])

        x, y, yaw = world.car.pose()
        car_offset_m = float(lane_offsets(world.road, x, y, yaw, lane, [0.0])[0])

        for name in self.front:
            e = estimates[name]
            self.metrics.add_offset(name, e.offset_m if e.valid else None, true_offset(e.x_m))
            self.metrics.add_lane(name, tracked[name], sensed.center)
        ref = estimates[REFERENCE]
        self.metrics.add_offset(REFERENCE, selection.reference_m if ref.valid else None,
                                true_offset(ref.x_m))
        self.metrics.add_offset(FUSED, offset, true_offset(est.offset_lookahead_m))
        self.metrics.add_lane(FUSED, centre, sensed.center)
        if centre is None:
            self.metrics.add_no_estimate()
        outside = self._wheels_outside_lane()
        if outside:
            events.append("lane departure: a wheel crossed a lane boundary")
        self.metrics.add_car(car_offset_m, outside)
        self.metrics.add_selection(self._chosen, selection.reference_repaired)
        return StepResult(
            index=self.index, time_s=float(world.data.time), frames=frames, estimates=estimates,
            tracked=tracked, probabilities=np.asarray(selection.probabilities),
            selected=int(self._chosen), output_offset_m=offset, output_centre=centre,
            reference_m=selection.reference_m, reference_repaired=selection.reference_repaired,
            steer=steer, throttle=throttle, truth_offset_m=car_offset_m,
            truth_centre=sensed.center, pose=(x, y, yaw), sensed_pose=sensed_pose,
            speed_mps=world.car.speed_mps(), events=events,
            tracker_status=dict(self._tracker_status),
        )

    def _wheels_outside_lane(self) -> bool:
        world = self.world
        xy = world.data.geom_xpos[self._tyre_geoms, :2]
        _, r = world.road.local_coordinates(xy)
        centre = world.road.lane_center_r(self.scenario.road.ego_lane)
        return bool(np.any(np.abs(np.asarray(r) - centre) > world.road.lane_width_m / 2.0))

    # -- whole episodes --------------------------------------------------------------------
    @property
    def total_steps(self) -> int:
        return int(round(self.scenario.duration_s / self.dt_s))

    def run(self, seconds: float | None = None, progress=None) -> EpisodeReport:
        """Step to the end (or `seconds`); an interrupt still returns a partial report."""
        steps = self.total_steps if seconds is None else int(round(seconds / self.dt_s))
        completed = True
        try:
            for _ in range(steps):
                self.step()
                if progress is not None:
                    progress(self.index, steps)
        except KeyboardInterrupt:
            completed = False
        return self.report(completed)

    def report(self, completed: bool = True) -> EpisodeReport:
        return self.metrics.report(self.scenario.name, self.scenario.seed, self.dt_s,
                                   completed=completed,
                                   wall_s=time.perf_counter() - self._wall_start)

    def close(self) -> None:
        self.rig.close()
        self.recorder.close()

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
