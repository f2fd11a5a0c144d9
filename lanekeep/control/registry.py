"""Controllers by name: what turns the estimated lane and the car's sensors into steer and throttle.

    controller = make_controller("pid", ControlContext.of(scenario, geometry))
    steer, throttle = controller.control(estimate, signals)   # each control period

A controller sees only what a real car's controller could: the estimator's output (the lane
the MMAE hands on, estimators/lane_estimator.py) and the vehicle's sensor signals
(lanekeep/sensing/vehicle_sensors.py); nothing of the simulator's truth. The episode calls
`reset()` once
before the first step.

Built in: "pid" (the paper's eq. 9 steering PID with our improvements, or the paper's own in
`mode = "paper"`; the default) and "stanley" (lanekeep/control/stanley.py). Any other name may be an
import path `package.module:Class` or an entry point of the group `lanekeep.control.registry`
(lanekeep/core/plugins.py); it is called as `Class(context)` with the `ControlContext` of
lanekeep/control/base.py.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from lanekeep.control.base import ControlContext, Controller
from lanekeep.control.pid import PaperGains, SpeedController, SteeringPID
from lanekeep.control.stanley import StanleyController
from lanekeep.core import plugins
from lanekeep.core.config_io import ConfigError
from lanekeep.core.signals import VehicleSignals
from lanekeep.geometry.lane_poly import LanePoly

if TYPE_CHECKING:
    from lanekeep.estimators.lane_estimator import EstimatorOutput

__all__ = ["ControlContext", "Controller", "PidController", "StanleyController",
           "check_controller", "known_controllers", "lane_curvature", "make_controller"]


def lane_curvature(centre: np.ndarray, x_m: float) -> float:
    """Curvature of the lane polynomial at x: 2 c2 / (1 + y'^2)^1.5. A quadratic fitted to a
    tight arc over 4-20 m inflates c2 (it absorbs the arc's x^4 term), and 2 c2 alone would
    over-steer a 40 m radius turn by ~25%."""
    return float(LanePoly.of(centre).curvature_1pm(x_m))


class PidController:
    """The default: the steering PID of paper eq. 9 (lanekeep/control/pid.py) and the speed PI,
    or the adaptive cruise for the throttle when the context has one (lanekeep/control/acc.py).

    Default mode: feedback on the lane's offset and heading projected `control_lookahead_m`
    ahead, the lane's curvature there into the feed-forward, and the gains scheduled on the
    larger of that curvature and the car's own (gyro). Paper mode: eq. 9 on the output offset
    itself (the selected detection at its nearest row), Table 2's gains, the same schedule.
    """

    def __init__(self, context: ControlContext) -> None:
        self.context = context
        self.paper_mode = context.mode == "paper"
        self.steering = SteeringPID(context.dt_s, context.control_lookahead_m,
                                    context.wheelbase_m, context.max_steer_rad,
                                    paper_gains=PaperGains() if self.paper_mode else None)
        self.speed = SpeedController(context.target_speed_mps, context.dt_s)
        self.acc = context.adaptive_cruise()

    def reset(self) -> None:
        self.steering.reset()
        self.speed.reset()
        if self.acc is not None:
            self.acc.reset()

    def throttle(self, signals: VehicleSignals) -> float:
        """The speed PI toward the target speed, or the adaptive cruise's when it is on."""
        return self.speed(signals.speed_mps) if self.acc is None else self.acc(signals)

    def control(self, estimate: EstimatorOutput, signals: VehicleSignals
                ) -> tuple[float, float]:
        centre, speed = estimate.centre, signals.speed_mps
        path = signals.yaw_rate_rps / max(abs(speed), 1.0)  # the car's own curvature (gyro)
        if centre is None:
            steer = self.steering(None, speed)
        elif self.paper_mode:
            # The paper does not say how it tells a curvy road from a straight one; here the
            # larger of the lane's curvature there and the car's own path curvature (gyro yaw
            # rate / wheel speed) picks the gains: a short-range model fits straight lines,
            # and once the car turns, the gyro knows.
            lane = lane_curvature(centre, estimate.offset_x_m)
            curvature = max(lane, path, key=abs)
            steer = self.steering(estimate.offset_m, speed, curvature_1pm=curvature)
        else:
            # The linear terms at x_ctrl are the feedback; the curvature goes to the
            # feed-forward, not counted twice.
            x_ctrl = self.context.control_lookahead_m
            control_offset = -float(centre[0] + centre[1] * x_ctrl)
            curvature = lane_curvature(centre, x_ctrl)
            # The schedule, as in paper mode, also hears the gyro: a lane read straighter
            # than it is (its far markings hidden by traffic) leaves the soft straight set in
            # a curve the car is already turning through.
            steer = self.steering(control_offset, speed, curvature_1pm=curvature,
                                  schedule_curvature_1pm=max(curvature, path, key=abs))
        return steer, self.throttle(signals)


CONTROLLERS: dict[str, Callable[[ControlContext], Controller]] = {
    "pid": PidController,
    "stanley": StanleyController,
}


def known_controllers() -> list[str]:
    """Built-in names and those installed distributions register as entry points."""
    return sorted({*CONTROLLERS, *plugins.entry_point_names(plugins.CONTROLLERS)})


def check_controller(name: str, key: str = "") -> None:
    """Fail now, not mid-run, on a name that makes no controller (ConfigError naming it)."""
    plugins.resolve(name, plugins.CONTROLLERS, CONTROLLERS, key, known_controllers)


def make_controller(name: str, context: ControlContext) -> Controller:
    """The controller `name` (built-in, entry point or import path) built for `context`.

    Raises:
      ConfigError: an unknown name, a bad import path, or an object that is no Controller.
    """
    factory = plugins.resolve(name, plugins.CONTROLLERS, CONTROLLERS, "", known_controllers)
    controller = (factory(context) if name in CONTROLLERS
                  else plugins.build(name, plugins.CONTROLLERS, factory, context))
    if not isinstance(controller, Controller):
        missing = [a for a in ("control", "reset") if not callable(getattr(controller, a, None))]
        raise ConfigError("", "", f"controller {name!r} made a {type(controller).__name__}, "
                                  f"not a Controller (missing: {', '.join(missing)})")
    return controller
