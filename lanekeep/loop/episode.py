"""One closed-loop episode: sense, detect, track, select, control, actuate, score, record.

Each line of `Episode.step` is one call into one module (DESIGN.md's loop). The front
detectors each feed a Kalman lane tracker; the rear detector is the MMAE's reference (the
paper's "observer"); the MMAE selects (or fuses) the front models; the scenario's controller
(lanekeep/control/registry.py; by default the PID on the chosen lane's offset at the control
look-ahead, and the speed PI) steers and drives.

What the car knows is what a car has: the camera frames and its sensor signals
(lanekeep/sensing/vehicle_sensors.py: wheel odometry, IMU yaw rate, accelerations, steering
angle), dead-reckoned into the estimator's ego-motion (estimators/odometry.py). The
detectors, the estimator and the controller are built from the car's camera models, its
estimation and control settings and its spec sheet, never from the world. The simulator's
state (the car's true pose and speed, the MuJoCo state, the road, the scenario's conditions)
sits behind one gate, `self.truth` (lanekeep/scoring/gate.py), which only scoring (`_score`),
the recorder, the sensors and the renderer and image effects (`_sense`) are handed;
tests/loop/test_honest_loop.py proves that perception, estimation and control run without it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from lanekeep.control.registry import ControlContext, Controller, make_controller
from lanekeep.core.interrupts import stop_point, stop_requested
from lanekeep.core.signals import VehicleSignals
from lanekeep.core.timing import StageClock
from lanekeep.core.workers import threads_now
from lanekeep.detectors.base import Detector, LaneEstimate
from lanekeep.detectors.registry import builtin_family, front_labels, make_detector
from lanekeep.estimators.lane_estimator import EstimatorOutput, LaneEstimator
from lanekeep.estimators.odometry import DeadReckoning
from lanekeep.estimators.roll import RollFilter, corrected
from lanekeep.loop.detection import DetectionRunner, group_jobs
from lanekeep.loop.paper_mode import estimator_settings, front_detector_config, roll_compensation
from lanekeep.report.record import EpisodeInfo, NullRecorder, Recorder
from lanekeep.scenario.nuisance import with_nuisance
from lanekeep.scenario.schema import Scenario
from lanekeep.scenario.streams import stream_entropy
from lanekeep.scoring.departures import off_road_reason, wheels_outside_lane
from lanekeep.scoring.gate import Truth
from lanekeep.scoring.metrics import EpisodeReport
from lanekeep.scoring.step_score import REFERENCE, loop_metrics, score_estimates
from lanekeep.scoring.step_truth import StepTruth, step_truth
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.paint_visibility import visible_paint
from lanekeep.sensing.snapshot import make_effects
from lanekeep.sensing.vehicle_sensors import VehicleSensors
from lanekeep.world.build import SimulationError, World, build

TYRES = ("front_left_tyre", "front_right_tyre", "rear_left_tyre", "rear_right_tyre")

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

    @property
    def truth_offset_m(self) -> float:
        """The car's true lateral offset after the period (at `pose`)."""
        return self.truth.car_offset_m

    @property
    def truth_output_m(self) -> float:
        """The true offset at the output's look-ahead, where the frames were taken."""
        return self.truth.offset_at(self.output_x_m)

    @property
    def truth_centre(self) -> np.ndarray:
        """The true lane centre in the frame of `sensed_pose`."""
        return self.truth.centre


@dataclass
class Percept:
    """What the car has at the start of a control period, before it acts: its camera frames,
    its sensor signals, the detections and the estimator's output. `sensed_pose` (the true pose
    the frames were taken from) is for scoring only."""

    index: int
    time_s: float
    frames: dict[str, np.ndarray]
    signals: VehicleSignals
    estimates: dict[str, LaneEstimate]
    estimate: EstimatorOutput
    events: list[str]
    sensed_pose: tuple[float, float, float]


class Episode:
    """A closed-loop run of one scenario; `run()` steps it to the end and returns the report."""

    def __init__(self, scenario: Scenario, recorder: Recorder | None = None,
                 render_size: tuple[int, int] | None = None) -> None:
        # the seed's start and traffic timing (the file's own seed: its nominal drive)
        scenario = with_nuisance(scenario)
        world = build(scenario)
        # The gate to the truth: scoring, the recorder, the sensors and the renderer get it.
        self.truth = Truth(world, scenario)
        # What the car's perception, estimation and control are built from (settings only).
        self.estimation = est = scenario.estimation
        width, height = render_size or (scenario.camera.width, scenario.camera.height)
        self.rig = CameraRig(world.model, RenderSettings.of(scenario, width, height))
        # seed and name: scenarios on one seed draw independent noise (scenario/streams.py)
        self.rng = np.random.default_rng(stream_entropy(scenario))
        # One effects pipeline per camera: lens drops and the auto-exposure keep state.
        self.effects = make_effects(scenario, world, self.rig, self.rng)
        self.dt_s = scenario.control_period_s
        # keyed by label: a plug-in given by import path by its own `name` (core/plugins.py)
        labels = front_labels(est.front_detectors)
        # What the loop measured per built-in (paper mode's windows, the trackers' noise) goes
        # to a plug-in that subclasses one too (detectors/registry.py `builtin_family`).
        families = {label: builtin_family(name) or name
                    for label, name in zip(labels, est.front_detectors, strict=True)}
        self.front: dict[str, Detector] = {
            label: make_detector(name, self.rig.cameras["front"],
                                 front_detector_config(families[label], est.mode),
                                 self.rig.distortion("front"))
            for label, name in zip(labels, est.front_detectors, strict=True)
        }
        self.reference: Detector = make_detector(est.reference_detector,
                                                   self.rig.cameras[est.reference_camera],
                                                   distortion=self.rig.distortion(
                                                       est.reference_camera))
        self.roll = RollFilter(roll_compensation(est), self.dt_s)
        self.estimator = LaneEstimator(
            list(self.front),
            estimator_settings(est),
            reference_x_m=float(self.reference.x_ref),
            families=families,
        )
        geometry = world.car.geometry  # the car's spec sheet, not its state
        # The sensors draw from their own stream of the episode's generator, so that they do
        # not shift the image effects' draws (and a perfect-sensor run sees the same frames).
        self.sensors = VehicleSensors(scenario.sensors, self.dt_s, self.rng.spawn(1)[0])
        # The reference point is the middle of the wheelbase (lanekeep/world/vehicle.py).
        self.odometry = DeadReckoning(self.dt_s, geometry.wheelbase_m / 2.0)
        # [control] controller: "pid" (default), "stanley", an entry point or an import path
        self.controller: Controller = make_controller(scenario.control.controller,
                                                      ControlContext.of(scenario, geometry))
        self.controller.reset()
        self.metrics = loop_metrics(list(self.front))
        self.recorder: Recorder = recorder or NullRecorder()
        self.recorder.start(EpisodeInfo(world.road, dict(self.rig.cameras), list(self.front),
                                        float(self.dt_s),
                                        (geometry.length_m, geometry.width_m)))
        for detector in [*self.front.values(), self.reference]:
            detector.reset()
        self.index = 0
        self._percept: Percept | None = None  # sensed, not yet acted on
        self.detector_errors = 0
        self.clock = StageClock()  # wall time per stage (`lanekeep perf`)
        self.detection = DetectionRunner(threads_now)
        self._tyre_geoms = [world.model.geom(n).id for n in TYRES]
        self._wall_start = time.perf_counter()

    @property
    def world(self) -> World:
        """The simulator (truth): for tools outside the loop and the faces' privileged views.
        The loop itself reads it through `self.truth`."""
        return self.truth.world

    @property
    def scenario(self) -> Scenario:
        """The scenario as run (truth: its road and conditions), read through the gate."""
        return self.truth.scenario

    # -- the loop ------------------------------------------------------------------------------
    def observe(self) -> Percept:
        """The start of a control period: frames, sensor signals, detections and the estimate.

        An agent outside (the Gymnasium and dm_env faces) calls this, decides, then `act`s on
        it, so it acts on the frames of the same period as the built-in controller does. The
        percept is kept until `act` uses it: calling `observe` twice senses once.
        """
        if self._percept is None:
            self.clock.start()
            events: list[str] = []
            sensed_pose = self._true_pose()  # scoring: where the frames are taken from
            frames = self._sense()
            signals = self.sensors.sample(self.truth.car)
            estimates = self._roll_corrected(self._detect(frames, events), signals)
            estimate = self._estimate(estimates, signals)  # laps "track" and "mmae"
            events.extend(estimate.events)
            self._percept = Percept(index=self.index, time_s=self.truth.time_s(),
                                    frames=frames, signals=signals, estimates=estimates,
                                    estimate=estimate, events=events, sensed_pose=sensed_pose)
        return self._percept

    def act(self, action: tuple[float, float] | None = None) -> StepResult:
        """The rest of the control period: steer and throttle (the controller's, or `action`
        = (steer, throttle) from outside) on the latest percept, physics, scoring, recording."""
        percept = self.observe()
        self._percept = None
        clock = self.clock
        estimate, signals = percept.estimate, percept.signals
        steer, throttle = self._control(estimate, signals) if action is None else action
        clock.lap("control")
        self.truth.world.step(steer, throttle, self.dt_s)  # actuate: the simulator
        clock.lap("physics")
        result = self._score(percept.sensed_pose, percept.frames, percept.estimates, estimate,
                             signals, steer, throttle, percept.events)
        clock.lap("score")
        if self.recorder.wants_masks(self.index):
            result = replace(result, marking_masks_after=self._marking_masks())
        self.recorder.log_step(result)
        clock.lap("record")
        self.index += 1
        return result

    def step(self, action: tuple[float, float] | None = None) -> StepResult:
        """One control period (`observe`, then `act`). `action` = (steer, throttle) overrides
        the controller."""
        return self.act(action)

    def _sense(self) -> dict[str, np.ndarray]:
        """The cameras' frames: the renderer and the image effects image the true scene
        (motion blur follows the true motion)."""
        data, car = self.truth.data, self.truth.car
        frames = {}
        for name in self.rig.CAMERA_NAMES:
            depth = None
            if self.rig.settings.depth:
                rgb, depth = self.rig.render_rgb_depth(data, name)
            else:
                rgb = self.rig.render_rgb(data, name)
            self.clock.lap(f"render_{name}")
            frames[name] = self.effects[name](rgb, self.rng, speed_mps=car.speed_mps(),
                                              depth_m=depth)
            self.clock.lap(f"effects_{name}")
        return frames

    def _detect(self, frames, events) -> dict[str, LaneEstimate]:
        """Every detector's estimate of this step's frames (lanekeep/loop/detection.py: on two
        threads when this process may use two cores); a detector that fails counts as a miss,
        with an event, in the detectors' order whatever thread ran it."""
        est = self.estimation
        named = [(name, detector, frames["front"]) for name, detector in self.front.items()]
        named.append((REFERENCE, self.reference, frames[est.reference_camera]))
        parallel = self.detection.parallel_now()
        jobs = group_jobs(named, parallel)
        results = self.detection.run(jobs, parallel)
        by_name = {name: detected for job, job_results in zip(jobs, results, strict=True)
                   for name, detected in zip(job.names, job_results, strict=True)}
        out, own_s = {}, {}
        for name, _, _ in named:
            detected = by_name[name]
            if detected.event:
                self.detector_errors += 1
                events.append(f"detector {name} {detected.event}")
            out[name] = detected.estimate
            own_s["detect_reference" if name == REFERENCE else f"detect_{name}"] = detected.seconds
        self.clock.share(own_s)  # on two threads: the section's wall time, shared out
        return out

    def _roll_corrected(self, estimates: dict[str, LaneEstimate], signals: VehicleSignals
                        ) -> dict[str, LaneEstimate]:
        """Each camera's lanes with the body roll's offset error taken out (estimators/roll.py),
        from the lateral accelerometer."""
        self.roll.update(signals.accel_lat_mps2)
        camera = {REFERENCE: self.estimation.reference_camera}
        return {name: corrected(e, self.roll.offset_error_m(camera.get(name, "front")))
                for name, e in estimates.items()}

    def _estimate(self, estimates: dict[str, LaneEstimate], signals: VehicleSignals
                  ) -> EstimatorOutput:
        front = {name: estimates[name] for name in self.front}
        ego = self.odometry.update(signals.speed_mps, signals.yaw_rate_rps)
        return self.estimator.update(front, estimates[REFERENCE], ego, lap=self.clock.lap)

    def _control(self, estimate: EstimatorOutput, signals: VehicleSignals
                 ) -> tuple[float, float]:
        """The scenario's controller (lanekeep/control/registry.py): estimate and sensors only."""
        steer, throttle = self.controller.control(estimate, signals)
        return float(steer), float(throttle)

    def _true_pose(self) -> tuple[float, float, float]:
        """The car's true pose, for scoring only."""
        return self.truth.pose()

    def _score(self, sensed_pose, frames, estimates, estimate: EstimatorOutput,
               signals: VehicleSignals, steer, throttle, events) -> StepResult:
        """Estimates against the truth of the pose their frames were taken from; the car's own
        lateral error and lane departures at its pose after the control period.

        Per front model two columns: its raw detection (at the detector's own look-ahead) and
        its own Kalman track (at the output's look-ahead, like the fused output).
        """
        gate = self.truth
        world, lane = gate.world, gate.lane
        pose_after = self._true_pose()
        truth = step_truth(
            world.road, lane, sensed_pose, pose_after,
            [e.x_m for e in estimates.values()] + [estimate.offset_x_m, estimate.reference_x_m],
            self.metrics.ade_points_m,
            drawn_lookaheads_m=(0.0, self.estimation.offset_lookahead_m))
        track_offsets = score_estimates(self.metrics, list(self.front), estimates, estimate,
                                        truth, self.estimator.centre_of)
        tyres_xy = world.data.geom_xpos[self._tyre_geoms, :2]
        outside = wheels_outside_lane(world.road, lane, tyres_xy)
        off_road = off_road_reason(world.road, world.layout, tyres_xy, truth.car_offset_m,
                                   gate.scenario.criteria.off_road_distance_m,
                                   float(world.data.time))
        if off_road:
            events.append(off_road)
        if outside:
            events.append("lane departure: a wheel crossed a lane boundary")
        self.metrics.add_car(truth.car_offset_m, outside)
        selection = estimate.selection
        self.metrics.add_selection(estimate.selected, selection.reference_repaired)
        return StepResult(
            index=self.index, time_s=float(world.data.time), frames=frames, estimates=estimates,
            tracked=estimate.tracked, track_offsets_m=track_offsets,
            probabilities=np.asarray(selection.probabilities),
            selected=int(estimate.selected), output_offset_m=estimate.offset_m,
            output_x_m=estimate.offset_x_m, output_centre=estimate.centre,
            reference_m=selection.reference_m, reference_x_m=estimate.reference_x_m,
            reference_repaired=selection.reference_repaired,
            mmae_residuals_m=np.asarray(selection.residuals_m, dtype=float),
            steer=steer, throttle=throttle, truth=truth, pose=pose_after,
            sensed_pose=sensed_pose, speed_mps=world.car.speed_mps(), signals=signals,
            events=events, tracker_status=dict(estimate.tracker_status), off_road=off_road,
        )

    def _marking_masks(self) -> dict[str, np.ndarray]:
        """Per camera, the paint the camera can see now (for the recording): the segmentation
        render's paint, less what fog or darkness hides (lanekeep/sensing/paint_visibility.py)."""
        world, masks = self.truth.world, {}
        data = world.data
        for name in self.rig.CAMERA_NAMES:
            paint = world.marking_mask(self.rig.render_segmentation(data, name))
            bare, depth = self.rig.render_rgb_depth(data, name)
            fx = self.effects[name]
            weather = fx.weather
            masks[name] = visible_paint(
                paint, bare, weather.range_m(depth), weather.extinction_per_m,
                float(weather.airlight.mean()), fx.sensor.gain).astype(np.uint8)
        return masks

    # -- whole episodes --------------------------------------------------------------------
    @property
    def total_steps(self) -> int:
        return int(round(self.truth.scenario.duration_s / self.dt_s))

    def run(self, seconds: float | None = None,
            on_step: Callable[[StepResult, int], None] | None = None) -> EpisodeReport:
        """Step to the end (or `seconds`); an interrupt still returns a partial report.

        `on_step(result, total_steps)` sees every step as it is made (a trace for plots, a
        progress bar); the report says `completed = False`, its `status` and why
        (`stop_reason`) after Ctrl-C ("interrupted"), when the physics went unstable
        (lanekeep.world.build.SimulationError: "unstable") or once the car left the road
        ("off_road": the step on which it left is scored, since its frames were taken on the
        road and its end pose is the failure the criteria must see; no later step is).
        """
        steps = self.total_steps if seconds is None else int(round(seconds / self.dt_s))
        status, reason = "completed", ""
        try:
            with stop_point():  # under the CLI a stop signal ends the loop between steps
                for _ in range(steps):
                    if stop_requested():
                        status = reason = "interrupted"
                        break
                    result = self.step()
                    if on_step is not None:
                        on_step(result, steps)
                    if result.off_road:
                        status, reason = "off_road", result.off_road
                        break
        except KeyboardInterrupt:
            status = reason = "interrupted"
        except SimulationError as err:  # the steps so far stand; the recording is kept
            status, reason = "unstable", str(err)
        return self.report(status == "completed", reason, status=status)

    def report(self, completed: bool = True, stop_reason: str = "",
               status: str | None = None) -> EpisodeReport:
        scenario = self.truth.scenario
        return self.metrics.report(scenario.name, scenario.seed, self.dt_s,
                                   completed=completed,
                                   wall_s=time.perf_counter() - self._wall_start,
                                   stop_reason=stop_reason, status=status)

    def close(self) -> None:
        self.detection.close()
        self.rig.close()
        self.recorder.close()

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
