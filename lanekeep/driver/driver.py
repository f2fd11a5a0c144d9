"""The car's side of the loop: frames and sensor signals in, a command and what it believed out.

    detect    every front detector on the front frame, the reference on its camera's frame
              (lanekeep/driver/detection.py: on two threads where two cores are free)
    roll      each camera's lanes with the body roll's offset error taken out (estimators/roll.py)
    estimate  odometry (estimators/odometry.py), trackers, MMAE, output (estimators/)
    control   the configured controller (lanekeep/control/registry.py)

An agent outside (the Gymnasium and dm_env faces) calls `perceive`, decides its own command,
and never calls `command`; the built-in loop calls `step`, which is both.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from lanekeep.control.registry import Controller, make_controller
from lanekeep.core.signals import VehicleSignals
from lanekeep.core.steps import Command, Observation
from lanekeep.core.timing import StageClock
from lanekeep.core.workers import threads_now
from lanekeep.detectors.base import Detector, LaneEstimate
from lanekeep.detectors.registry import make_detector
from lanekeep.driver.config import DriverConfig
from lanekeep.driver.detection import DetectionRunner, group_jobs
from lanekeep.estimators.lane_estimator import EstimatorOutput, LaneEstimator
from lanekeep.estimators.odometry import DeadReckoning, EgoMotion
from lanekeep.estimators.roll import RollFilter, corrected

REFERENCE = "reference"  # the key of the reference's estimate beside the front models' labels


@dataclass(frozen=True)
class Belief:
    """What the driver made of one observation: every detector's estimate (roll-corrected;
    the front models by label, the reference under REFERENCE), the estimator's output, and
    the step's events (a detector fault, the estimator's notes)."""

    estimates: Mapping[str, LaneEstimate]
    estimate: EstimatorOutput
    events: list[str] = field(default_factory=list)


class Driver:
    """Detectors, filters, estimator and controller of one car, built from `config` alone."""

    def __init__(self, config: DriverConfig, clock: StageClock | None = None) -> None:
        self.config = config
        est = config.estimation
        self.clock = clock or StageClock()
        cameras, lens = config.cameras, config.distortions
        families = config.families
        self.front: dict[str, Detector] = {
            label: make_detector(name, cameras["front"], config.front_detector_config(label),
                                 lens.get("front"))
            for label, name in zip(config.front_labels, est.front_detectors, strict=True)
        }
        self.reference: Detector = make_detector(est.reference_detector,
                                                   cameras[est.reference_camera],
                                                   config.detectors,
                                                   distortion=lens.get(est.reference_camera))
        self.roll = RollFilter(config.roll, config.period_s)
        self.estimator = LaneEstimator(list(self.front), config.estimator,
                                       reference_x_m=float(self.reference.x_ref),
                                       families=families)
        self.odometry = DeadReckoning(config.period_s, config.odometry_lever_m)
        self.controller: Controller = make_controller(config.controller, config.control)
        self.controller.reset()
        for detector in [*self.front.values(), self.reference]:
            detector.reset()
        self.detection = DetectionRunner(threads_now)
        self.detector_errors = 0

    @property
    def centre_of(self) -> Callable[[LaneEstimate], np.ndarray | None]:
        """A detection's centre line as the estimator would track it (its lane-width
        centring): what scoring compares a raw detection's lane with."""
        return self.estimator.centre_of

    def step(self, observation: Observation) -> tuple[Command, Belief]:
        """One control period: perceive, then command."""
        belief = self.perceive(observation)
        return self.command(belief, observation.signals), belief

    def perceive(self, observation: Observation) -> Belief:
        """Detections, roll correction and the estimator's update for one observation."""
        events: list[str] = []
        signals = observation.signals
        ego = self.odometry.update(signals.speed_mps, signals.yaw_rate_rps)
        self._tell_motion(ego)
        detected = self.detect(observation.frames, events)
        estimates = self._roll_corrected(detected, signals)
        estimate = self._estimate(estimates, ego)  # laps "track" and "mmae"
        events.extend(estimate.events)
        return Belief(estimates=estimates, estimate=estimate, events=events)

    def command(self, belief: Belief, signals: VehicleSignals) -> Command:
        """The controller's steer and throttle for a belief (estimate and sensors only)."""
        steer, throttle = self.controller.control(belief.estimate, signals)
        return Command(float(steer), float(throttle))

    def detect(self, frames: Mapping[str, np.ndarray], events: list[str]
                ) -> dict[str, LaneEstimate]:
        """Every detector's estimate of this step's frames, in the detectors' order whatever
        thread ran it; a detector that fails counts as a miss, with an event."""
        named = [(name, detector, frames["front"]) for name, detector in self.front.items()]
        named.append((REFERENCE, self.reference, frames[self.config.estimation.reference_camera]))
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
        """Each camera's lanes less the body roll's offset error, from the lateral
        accelerometer."""
        self.roll.update(signals.accel_lat_mps2)
        camera = {REFERENCE: self.config.estimation.reference_camera}
        return {name: corrected(e, self.roll.offset_error_m(camera.get(name, "front")))
                for name, e in estimates.items()}

    def _tell_motion(self, ego: EgoMotion) -> None:
        """The period's motion, from wheel speed and yaw rate, to each detector that carries
        what it saw across frames (one with a `move` method: detectors/base.py)."""
        for detector in [*self.front.values(), self.reference]:
            move = getattr(detector, "move", None)
            if callable(move):
                move(ego.speed_mps, ego.yaw_rate_rps, ego.dt_s, ego.lateral_speed_mps)

    def _estimate(self, estimates: dict[str, LaneEstimate], ego: EgoMotion) -> EstimatorOutput:
        front = {name: estimates[name] for name in self.front}
        return self.estimator.update(front, estimates[REFERENCE], ego, lap=self.clock.lap)

    def close(self) -> None:
        self.detection.close()
