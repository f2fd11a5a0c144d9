"""Scoring one control period: the truth once (lanekeep/scoring/step_truth.py), every estimate
against it (step_score.py), the car's own lateral error, lane departures and leaving the road
from where its tyres truly are (departures.py), its safety among other vehicles (gap, TTC,
contact, braking: safety.py), into the episode's metrics and one `StepResult`. The only part
of an episode besides the recorder that reads the world."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from lanekeep.core.steps import Command, Observation
from lanekeep.detectors.base import LaneEstimate
from lanekeep.driver.driver import Belief
from lanekeep.scoring.departures import off_road_reason, wheels_outside_lane
from lanekeep.scoring.gate import Truth
from lanekeep.scoring.metrics import EpisodeReport
from lanekeep.scoring.safety import StepSafety, collision_reason, step_safety
from lanekeep.scoring.step_result import StepResult
from lanekeep.scoring.step_score import loop_metrics, score_estimates
from lanekeep.scoring.step_truth import step_truth
from lanekeep.scoring.truth import frenet

TYRES = ("front_left_tyre", "front_right_tyre", "rear_left_tyre", "rear_right_tyre")


class StepScorer:
    """Scores an episode's steps against its truth and keeps its metrics."""

    def __init__(self, truth: Truth, models: Sequence[str], offset_lookahead_m: float,
                 centre_of: Callable[[LaneEstimate], np.ndarray | None]) -> None:
        """`models`: the front models' labels; `offset_lookahead_m`: where the recorder draws
        the output; `centre_of`: a detection's centre line as the estimator tracks it."""
        self.truth = truth
        self.models = list(models)
        self.offset_lookahead_m = offset_lookahead_m
        self.centre_of = centre_of
        self.metrics = loop_metrics(self.models)
        self.tyre_geoms = [truth.model.geom(n).id for n in TYRES]
        geometry = truth.car.geometry
        self.car_size_m = (geometry.length_m, geometry.width_m)
        # The car's true forward speed at the end of the last scored period (at the start,
        # before the first): its change over a period is the car's acceleration.
        self._speed_then = (truth.time_s(), truth.car.speed_mps())

    def pose(self) -> tuple[float, float, float]:
        """The car's true pose now: where the next frames are taken from."""
        return self.truth.pose()

    def score(self, index: int, sensed_pose: tuple[float, float, float],
              observation: Observation, belief: Belief, command: Command) -> StepResult:
        """The step's estimates against the truth of the pose their frames were taken from;
        the car's own lateral error and departures at its pose after the control period.

        Per front model two columns: its raw detection (at the detector's own look-ahead) and
        its own Kalman track (at the output's look-ahead, like the fused output)."""
        gate = self.truth
        world, lane = gate.world, gate.lane
        estimates, estimate = belief.estimates, belief.estimate
        events = list(belief.events)
        pose_after = gate.pose()
        truth = step_truth(
            world.road, lane, sensed_pose, pose_after,
            [e.x_m for e in estimates.values()] + [estimate.offset_x_m, estimate.reference_x_m],
            self.metrics.ade_points_m,
            drawn_lookaheads_m=(0.0, self.offset_lookahead_m))
        track_offsets = score_estimates(self.metrics, self.models, estimates, estimate,
                                        truth, self.centre_of)
        tyres_xy = world.data.geom_xpos[self.tyre_geoms, :2]
        outside = wheels_outside_lane(world.road, lane, tyres_xy)
        off_road = off_road_reason(world.road, world.layout, tyres_xy, truth.car_offset_m,
                                   gate.scenario.criteria.off_road_distance_m,
                                   float(world.data.time))
        if off_road:
            events.append(off_road)
        if outside:
            events.append("lane departure: a wheel crossed a lane boundary")
        self.metrics.add_car(truth.car_offset_m, outside)
        time_s, speed = float(world.data.time), world.car.speed_mps()
        safety = self._safety(pose_after, speed, time_s)
        self.metrics.add_safety(safety)
        collision = collision_reason(safety.collided_with, time_s)
        if collision:
            events.append(collision)
        selection = estimate.selection
        self.metrics.add_selection(estimate.selected, selection.reference_repaired)
        return StepResult(
            index=index, time_s=time_s, frames=dict(observation.frames),
            estimates=dict(estimates), tracked=estimate.tracked, track_offsets_m=track_offsets,
            probabilities=np.asarray(selection.probabilities),
            selected=int(estimate.selected), output_offset_m=estimate.offset_m,
            output_x_m=estimate.offset_x_m, output_centre=estimate.centre,
            reference_m=selection.reference_m, reference_x_m=estimate.reference_x_m,
            reference_repaired=selection.reference_repaired,
            mmae_residuals_m=np.asarray(selection.residuals_m, dtype=float),
            steer=command.steer, throttle=command.throttle, truth=truth, pose=pose_after,
            sensed_pose=sensed_pose, speed_mps=speed,
            signals=observation.signals, events=events,
            tracker_status=dict(estimate.tracker_status), off_road=off_road,
            safety=safety, collision=collision,
        )

    def _safety(self, pose: tuple[float, float, float], speed_mps: float, time_s: float
                ) -> StepSafety:
        """The car among the other vehicles at `pose`, and its acceleration over the period
        (its forward speed's change since the last scored period)."""
        then_s, speed_then = self._speed_then
        self._speed_then = (time_s, speed_mps)
        accel = (speed_mps - speed_then) / (time_s - then_s) if time_s > then_s else 0.0
        road = self.truth.road
        s, r = frenet(road, pose[:2])
        return step_safety(road, pose, s, r, speed_mps, self.car_size_m, accel,
                           self.truth.vehicles())

    def report(self, dt_s: float, completed: bool, wall_s: float, stop_reason: str = "",
               status: str | None = None) -> EpisodeReport:
        scenario = self.truth.scenario
        return self.metrics.report(scenario.name, scenario.seed, dt_s, completed=completed,
                                   wall_s=wall_s, stop_reason=stop_reason, status=status)
