"""Each hole the old honesty guard left open, as a leak the guard (tests/truth_guard.py) must
catch: a plug-in controller, detector or estimator that reads the MuJoCo state
(`world.data.qpos`), the road geometry (`road.segments[0].curvature_1pm`), the scenario's
conditions (`scenario.conditions`) or what the conditions laid (`world.conditions.shaded`).

Two ways a plug-in may get at the truth: handed it when built (a loop that passes the world
on: the guard refuses the episode before it runs) or found on its own at run time (here by
searching the heap: every read of it raises, whoever is up the stack).
"""

from __future__ import annotations

import gc
from collections.abc import Callable

import numpy as np
import pytest
from helpers import small_scenario
from truth_guard import TruthLeak, guard_truth

from lanekeep.loop.episode import Episode


class _Leaky:
    """A car-side part that does its job (the wrapped part's) and reads the truth besides."""

    def __init__(self, inner, find: Callable[[], object], read: Callable[[object], object]):
        self.inner, self.find, self.read = inner, find, read

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def leak(self) -> None:
        self.read(self.find())


class LeakyController(_Leaky):
    def reset(self) -> None:
        self.inner.reset()

    def control(self, estimate, signals):
        self.leak()
        return self.inner.control(estimate, signals)


class LeakyDetector(_Leaky):
    def reset(self) -> None:
        self.inner.reset()

    def detect(self, frame):
        self.leak()
        return self.inner.detect(frame)


class LeakyEstimator(_Leaky):
    def update(self, detections, reference, ego, lap):
        self.leak()
        return self.inner.update(detections, reference, ego, lap=lap)


def _install(episode: Episode, part: str, leaky: Callable[[object], _Leaky]) -> None:
    if part == "controller":
        episode.driver.controller = leaky(episode.driver.controller)
    elif part == "detector":
        episode.driver.front["hough"] = leaky(episode.driver.front["hough"])
    else:
        episode.driver.estimator = leaky(episode.driver.estimator)


_LEAKY = {"controller": LeakyController, "detector": LeakyDetector,
          "estimator": LeakyEstimator}

# hole -> (the part that leaks, the truth object it gets at, its read, what the guard says)
HOLES = {
    "world.data.qpos": ("controller", lambda t: t.world, lambda w: w.data.qpos,
                        r"World\.data read while controller"),
    "road.segments[0].curvature_1pm": ("detector", lambda t: t.road,
                                       lambda r: r.segments[0].curvature_1pm,
                                       r"Road\.segments read while detector"),
    "scenario.conditions": ("estimator", lambda t: t.scenario, lambda s: s.conditions,
                            r"Scenario\.conditions read while estimator"),
    "world.conditions.shaded": ("controller", lambda t: t.world,
                                lambda w: w.conditions.shaded(np.zeros(2)),
                                r"World\.conditions read while controller"),
}


def _episode() -> Episode:
    """Case 4 (a shaded straight: it has cast shadows) with the classical models only, small:
    what leaks is the point here, not how well the car drives."""
    scenario = small_scenario("case4_half_shade_straight", 1.0, estimation={
        "front_detectors": ("hough", "sliding_window"), "reference_detector": "sliding_window"})
    return Episode(scenario, render_size=(320, 180))


def _by_id(target: int) -> object:
    return next(o for o in gc.get_objects() if id(o) == target)


@pytest.mark.parametrize("hole", list(HOLES))
def test_a_plug_in_that_finds_the_truth_is_caught_reading_it(hole):
    part, target, read, says = HOLES[hole]
    with pytest.raises(TruthLeak, match=says), _episode() as episode:
        target_id = id(target(episode.truth))  # a number, not a reference: found at run time
        _install(episode, part, lambda inner: _LEAKY[part](inner, lambda: _by_id(target_id),
                                                           read))
        guard_truth(episode)
        episode.step()


def test_a_plug_in_handed_the_truth_is_refused_before_the_run():
    with _episode() as episode:
        parts = {"controller": episode.driver.controller, "detector": episode.driver.front["hough"],
                 "estimator": episode.driver.estimator}
        for hole, (part, target, read, _) in HOLES.items():
            obj = target(episode.truth)
            _install(episode, part, lambda inner, part=part, obj=obj, read=read:
                     _LEAKY[part](inner, lambda: obj, read))
            with pytest.raises(TruthLeak, match="holds the truth") as caught:
                guard_truth(episode)
            assert f"{part}" in str(caught.value), hole
            _install(episode, part, lambda inner, part=part: parts[part])  # put it back
        guard_truth(episode)  # the honest parts again: no leak
