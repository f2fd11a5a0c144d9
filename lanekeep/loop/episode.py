"""One closed-loop episode: a short loop over the simulator, the driver and the scorer.

    sense     Simulator.sense() -> Observation(frames, signals)    lanekeep/sensing/simulator.py
    drive     Driver.step(observation) -> (Command, Belief)          lanekeep/driver/
    actuate   Simulator.actuate(command): physics, traffic
    score     StepScorer.score(...) -> StepResult                    lanekeep/scoring/step_scorer.py
    record    Recorder.log_step(result)                              lanekeep/report/record.py

The driver is built from a `DriverConfig` (the scenario's estimation and control settings, the
car's spec sheet and its cameras' models), never from the world, and its package cannot import
the world, sensing, scoring or MuJoCo (tests/project/test_layers.py): what the car knows is
what a car has. The simulator's truth sits behind one gate, `self.truth`
(lanekeep/scoring/gate.py), handed to the scorer and the recorder only.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

from lanekeep.control.acc import acc_settings
from lanekeep.core.interrupts import stop_point, stop_requested
from lanekeep.core.steps import Command
from lanekeep.core.timing import StageClock
from lanekeep.driver.config import DriverConfig
from lanekeep.driver.driver import Driver
from lanekeep.report.record import EpisodeInfo, NullRecorder, Recorder
from lanekeep.scenario.nuisance import with_nuisance
from lanekeep.scenario.schema import Scenario
from lanekeep.scoring.gate import Truth
from lanekeep.scoring.metrics import EpisodeReport
from lanekeep.scoring.step_result import Percept, StepResult
from lanekeep.scoring.step_scorer import StepScorer
from lanekeep.sensing.simulator import Simulator
from lanekeep.world.build import SimulationError, World

__all__ = ["Episode", "Percept", "StepResult", "driver_config"]


def driver_config(scenario: Scenario, simulator: Simulator) -> DriverConfig:
    """The driver's settings (the scenario's estimation and control sections) and the car's
    spec sheet (from the simulator's car and cameras); nothing of the world."""
    return DriverConfig(estimation=scenario.estimation, controller=scenario.control.controller,
                        period_s=scenario.control_period_s,
                        target_speed_mps=scenario.target_speed_mps, car=simulator.car,
                        cameras=simulator.cameras, distortions=simulator.distortions,
                        acc=acc_settings(scenario.control, scenario.estimation.mode),
                        detectors=scenario.detectors)


class Episode:
    """A closed-loop run of one scenario; `run()` steps it to the end and returns the report."""

    def __init__(self, scenario: Scenario, recorder: Recorder | None = None,
                 render_size: tuple[int, int] | None = None) -> None:
        scenario = with_nuisance(scenario)  # the seed's start and traffic timing
        self.clock = StageClock()  # wall time per stage (`lanekeep perf`)
        self.simulator = Simulator(scenario, render_size, self.clock)
        # The gate to the truth: the scorer and the recorder get it, the driver never.
        self.truth = Truth(self.simulator.world, scenario)
        self.dt_s = scenario.control_period_s
        self._new_driver_and_scorer()
        self.recorder: Recorder = recorder or NullRecorder()
        car = self.simulator.car
        self.recorder.start(EpisodeInfo(self.truth.road, self.simulator.cameras,
                                        list(self.driver.front), float(self.dt_s),
                                        (car.length_m, car.width_m)))

    def _new_driver_and_scorer(self) -> None:
        scenario = self.truth.scenario
        self.driver = Driver(driver_config(scenario, self.simulator), self.clock)
        self.scorer = StepScorer(self.truth, list(self.driver.front),
                                 scenario.estimation.offset_lookahead_m, self.driver.centre_of)
        self.index = 0
        self._percept: Percept | None = None  # sensed, not yet acted on
        self._wall_start = time.perf_counter()

    def restart(self) -> None:
        """The same drive again from its start, on the same world (dm_control resets its
        physics in place): the simulator restarted, a new driver and scorer."""
        self.driver.close()
        self.simulator.restart()
        self._new_driver_and_scorer()

    @property
    def world(self) -> World:
        """The simulator (truth): for tools outside the loop and the faces' privileged views."""
        return self.truth.world

    @property
    def scenario(self) -> Scenario:
        """The scenario as run (truth: its road and conditions), read through the gate."""
        return self.truth.scenario

    @property
    def detector_errors(self) -> int:
        return self.driver.detector_errors

    # -- the loop ------------------------------------------------------------------------------
    def observe(self) -> Percept:
        """The start of a control period: the observation and the driver's belief.

        An agent outside (the Gymnasium and dm_env faces) calls this, decides, then `act`s on
        it, so it acts on the frames of the same period as the built-in controller does. The
        percept is kept until `act` uses it: calling `observe` twice senses once.
        """
        if self._percept is None:
            self.clock.start()
            sensed_pose = self.scorer.pose()  # scoring: where the frames are taken from
            observation = self.simulator.sense()
            belief = self.driver.perceive(observation)
            self._percept = Percept(self.index, observation, belief, sensed_pose)
        return self._percept

    def act(self, action: tuple[float, float] | None = None) -> StepResult:
        """The rest of the control period: the driver's command (or `action` = (steer,
        throttle) from outside) on the latest percept, physics, scoring, recording."""
        percept = self.observe()
        self.forget_percept()
        clock = self.clock
        command = (self.driver.command(percept.belief, percept.signals) if action is None
                   else Command(*action))
        clock.lap("control")
        self.simulator.actuate(command)  # laps "physics" and "traffic"
        return self.conclude(percept, command)

    def forget_percept(self) -> None:
        """The percept is being acted on: the next `observe` senses a new period."""
        self._percept = None

    def conclude(self, percept: Percept, command: Command) -> StepResult:
        """The end of a control period whose command has been actuated: score, record, count
        (dm_control's Environment steps the physics itself and calls this after)."""
        clock = self.clock
        result = self.scorer.score(self.index, percept.sensed_pose, percept.observation,
                                   percept.belief, command)
        clock.lap("score")
        if self.recorder.wants_masks(self.index):
            result = replace(result, marking_masks_after=self.simulator.marking_masks())
        self.recorder.log_step(result)
        clock.lap("record")
        self.index += 1
        return result

    def step(self, action: tuple[float, float] | None = None) -> StepResult:
        """One control period (`observe`, then `act`). `action` = (steer, throttle) overrides
        the controller."""
        return self.act(action)

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
        (lanekeep.world.build.SimulationError: "unstable"), once the car left the road
        ("off_road": the step on which it left is scored, since its frames were taken on the
        road and its end pose is the failure the criteria must see; no later step is) or once
        it touched another vehicle ("collision", likewise; the stop reason names the vehicle
        and the time). A step that ends both ways ends as a collision.
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
                    if result.collision:
                        status, reason = "collision", result.collision
                        break
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
        return self.scorer.report(self.dt_s, completed, time.perf_counter() - self._wall_start,
                                  stop_reason, status)

    def close(self) -> None:
        self.driver.close()
        self.simulator.close()
        self.recorder.close()

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
