"""What every controller is built from and the one method pair it meets, apart from any one
controller (the PID, Stanley, a plug-in), so that the registry and the loop depend on the
interface rather than on the PID's module.

A controller sees only what a real car's controller could: the estimator's output and the
vehicle's sensor signals, nothing of the simulator's truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from lanekeep.control.acc import AccSettings, AdaptiveCruise, acc_settings
from lanekeep.core.signals import VehicleSignals

if TYPE_CHECKING:
    from lanekeep.estimators.lane_estimator import EstimatorOutput
    from lanekeep.geometry.car import CarGeometry
    from lanekeep.scenario.schema import Scenario


@dataclass(frozen=True)
class ControlContext:
    """What a controller is built from: the scenario's control settings and the car's design
    figures (a spec sheet, not its state)."""

    dt_s: float  # control period
    target_speed_mps: float
    wheelbase_m: float
    max_steer_rad: float  # road-wheel angle at steer = +-1
    control_lookahead_m: float  # where the PID reads the lane ([estimation])
    mode: str = "default"  # [estimation] mode: "paper" runs the paper's own PID
    # The adaptive cruise's settings ([control] acc_*); None: it is off and the throttle holds
    # target_speed_mps. Paper mode never has one: the paper drives at a constant speed.
    acc: AccSettings | None = None

    @classmethod
    def of(cls, scenario: Scenario, geometry: CarGeometry) -> ControlContext:
        mode = "paper" if scenario.estimation.runs_paper("controller") else "default"
        return cls(scenario.control_period_s, scenario.target_speed_mps, geometry.wheelbase_m,
                   geometry.max_steer_rad, scenario.estimation.control_lookahead_m, mode,
                   acc_settings(scenario.control, scenario.estimation.mode))

    def adaptive_cruise(self) -> AdaptiveCruise | None:
        """The ACC this context asks for (lanekeep/control/acc.py), None when it is off."""
        if self.acc is None:
            return None
        return AdaptiveCruise(self.acc, self.target_speed_mps, self.dt_s)


@runtime_checkable
class Controller(Protocol):
    """Maps one step's estimate and sensor signals to (steer, throttle), each in [-1, 1]:
    steer + = left (1 = full lock), throttle - = brake. May keep state between steps."""

    def control(self, estimate: EstimatorOutput, signals: VehicleSignals
                ) -> tuple[float, float]: ...

    def reset(self) -> None:
        """Forget state carried between steps (a new episode)."""
        ...
