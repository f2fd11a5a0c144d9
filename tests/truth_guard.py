"""The truth guard: wraps an episode's car, road and road description so that any read of the
simulator's truth outside scoring, recording, the sensors and the simulator raises `TruthLeak`.
Shared by the honesty tests of the loop and of the controllers."""

from __future__ import annotations

import sys

from lanekeep.loop.episode import Episode

# (module, function) pairs allowed to read the truth; a module alone allows all its functions.
# By module name, not file path: CI runs the installed package, not the checkout.
ALLOWED = {
    ("lanekeep.loop.episode", "_true_pose"),
    ("lanekeep.loop.episode", "_score"),
    ("lanekeep.loop.episode", "_sense"),  # motion blur follows the true motion
    ("lanekeep.sensing.vehicle_sensors", None),  # the sensors measure the true state
    ("lanekeep.world.build", None),  # the simulator
    ("lanekeep.world.traffic", None),
    ("lanekeep.report.record", None),
}
CAR_READS = ("pose", "rotation", "velocity_body", "speed_mps", "lateral_speed_mps",
             "yaw_rate_rps", "steer_angle_rad", "wheel_speeds_rps")
ROAD_READS = ("heading_at", "curvature_at", "position", "local_coordinates", "segment_bounds",
              "boundary_r", "lane_center_r", "marking_pieces")


class TruthLeak(AssertionError):
    """Raised when the loop reads simulator truth outside scoring and recording."""


def _allowed_caller() -> bool:
    frame = sys._getframe(2)
    while frame is not None:
        module = frame.f_globals.get("__name__", "")
        if (module, frame.f_code.co_name) in ALLOWED or (module, None) in ALLOWED:
            return True
        frame = frame.f_back
    return False


def _check(what: str) -> None:
    if not _allowed_caller():
        raise TruthLeak(f"{what} read outside scoring/recording")


def _guarded_class(cls: type, methods: tuple[str, ...], attributes: tuple[str, ...]) -> type:
    namespace = {}
    for name in methods:
        def method(self, *args, _name=name, **kwargs):
            _check(f"{cls.__name__}.{_name}")
            return getattr(super(guarded, self), _name)(*args, **kwargs)
        namespace[name] = method
    for name in attributes:
        def getter(self, _name=name):
            _check(f"{cls.__name__}.{_name}")
            return self.__dict__[_name]
        namespace[name] = property(getter)
    guarded = type(f"Guarded{cls.__name__}", (cls,), namespace)
    return guarded


class _GuardedConfig:
    """A read-guarded view of a frozen dataclass (the scenario's road description)."""

    def __init__(self, config) -> None:
        object.__setattr__(self, "_config", config)

    def __getattr__(self, name):
        _check(f"scenario.road.{name}")
        return getattr(self._config, name)


def guard_truth(episode: Episode) -> None:
    world = episode.world
    world.car.__class__ = _guarded_class(type(world.car), CAR_READS, ())
    world.road.__class__ = _guarded_class(type(world.road), ROAD_READS,
                                          ("lane_width_m", "n_lanes"))
    object.__setattr__(episode.scenario, "road", _GuardedConfig(episode.scenario.road))
