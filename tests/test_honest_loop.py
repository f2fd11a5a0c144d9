"""The loop's honesty boundary: perception, estimation and control see camera frames and the
car's sensor signals only. The simulator's truth (the road, the car's true state, the
scenario's road description) may be read to score, to record, by the sensors themselves, to
image the scene and by the simulator; any other read raises `TruthLeak` here.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import pytest

from lanekeep.episode import Episode
from lanekeep.scenario import load_scenario

# (module, function) pairs allowed to read the truth; a module alone allows all its functions.
# By module name, not file path: CI runs the installed package, not the checkout.
ALLOWED = {
    ("lanekeep.episode", "_true_pose"),
    ("lanekeep.episode", "_score"),
    ("lanekeep.episode", "_wheels_outside_lane"),
    ("lanekeep.episode", "_sense"),  # motion blur follows the true motion
    ("lanekeep.sensors", None),  # the sensors measure the true state
    ("lanekeep.world", None),  # the simulator
    ("lanekeep.world_traffic", None),
    ("lanekeep.record", None),
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


def _short(name: str, seconds: float):
    scenario = load_scenario(name)
    return replace(scenario, duration_s=seconds)


@pytest.mark.parametrize("name", ["clear_curve", "case1_building_shadows"])
def test_an_episode_runs_to_its_end_without_reading_truth(name):
    scenario = _short(name, 4.0)
    with Episode(scenario, render_size=(640, 360)) as episode:
        guard_truth(episode)
        report = episode.run()
    assert report.completed
    assert report.steps == episode.total_steps == 40
    assert report.sources["fused"].valid_share > 0.9
    # Fair columns: each front model's raw detections and its own track, then the output.
    assert list(report.sources) == ["hough", "hough:track", "sliding_window",
                                    "sliding_window:track", "lanenet", "lanenet:track", "fused",
                                    "reference"]
    # (at half size, model #1 loses case 1's shaded lane for some steps: its track coasts)
    assert report.sources["hough:track"].valid_share > 0.5


def test_the_guard_catches_an_estimator_that_reads_the_true_pose(monkeypatch):
    with Episode(_short("clear_curve", 1.0), render_size=(640, 360)) as episode:
        guard_truth(episode)
        update = episode.estimator.update

        def leaky_update(detections, reference, ego, lap):
            episode.world.car.pose()  # what the old loop did for alignment
            return update(detections, reference, ego, lap=lap)

        monkeypatch.setattr(episode.estimator, "update", leaky_update)
        with pytest.raises(TruthLeak, match="pose"):
            episode.step()


def test_the_guard_catches_the_road_width_read_by_control():
    with Episode(_short("clear_curve", 1.0), render_size=(640, 360)) as episode:
        guard_truth(episode)
        with pytest.raises(TruthLeak, match="lane_width_m"):
            _ = episode.world.road.lane_width_m  # a read from the test's own (unlisted) code
