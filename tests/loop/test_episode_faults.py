"""Faults inside an episode: a detector that raises, returns NaN or the wrong type is a miss
with an event, and the episode goes on; physics that go unstable stop the episode with the
report so far, marked incomplete with the reason."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import small_scenario

from lanekeep.detectors.base import LaneEstimate
from lanekeep.loop.episode import Episode
from lanekeep.world.build import SimulationError


def _episode(seconds: float = 1.0) -> Episode:
    return Episode(small_scenario("clear_straight", seconds), render_size=(640, 360))


class _Faulty:
    """Wraps a detector; on the given steps it fails in the given way."""

    def __init__(self, inner, failure: str, steps: set[int]) -> None:
        self.inner, self.failure, self.steps, self.calls = inner, failure, steps, 0
        self.name, self.x_ref = inner.name, inner.x_ref

    def reset(self) -> None:
        self.inner.reset()

    def detect(self, frame: np.ndarray):
        k, self.calls = self.calls, self.calls + 1
        if k not in self.steps:
            return self.inner.detect(frame)
        if self.failure == "raise":
            raise IndexError("index 7 is out of bounds")  # not a ValueError: any exception
        if self.failure == "nan":
            return LaneEstimate(valid=True, offset_m=math.nan, x_m=4.0)  # raises in __post_init__
        return {"offset": 0.1}  # the wrong type


@pytest.mark.parametrize("failure", ["raise", "nan", "wrong_type"])
def test_a_faulty_detector_is_a_miss_with_an_event_and_the_episode_goes_on(failure):
    with _episode() as episode:
        episode.driver.front["hough"] = _Faulty(episode.driver.front["hough"], failure, {3, 4})
        results = [episode.step() for _ in range(episode.total_steps)]
        report = episode.report()
    assert len(results) == 10 and report.completed
    for k in (3, 4):
        assert not results[k].estimates["hough"].valid
        assert any("detector hough" in e for e in results[k].events), results[k].events
    assert results[5].estimates["hough"].valid
    assert episode.detector_errors == 2
    # the two faults count as misses in the share, beside any step hough found nothing on
    assert report.sources["hough"].valid_share == pytest.approx(
        sum(r.estimates["hough"].valid for r in results) / len(results))
    assert report.sources["hough"].valid_share <= 0.8
    assert report.sources["fused"].valid_share == 1.0


def test_unstable_physics_stop_the_episode_with_the_report_so_far():
    with _episode(2.0) as episode:
        steps = []

        def on_step(result, total):
            steps.append(result.index)
            if result.index == 4:  # a runaway velocity, as a bad actuator or model would leave
                episode.world.data.qvel[0] = 1e12

        report = episode.run(on_step=on_step)
    assert not report.completed
    assert "unstable" in report.stop_reason and report.steps == 5 == len(steps)
    assert "STOPPED" in report.table() and "unstable" in report.table()
    assert math.isfinite(report.car_rms_cm)


def test_world_step_raises_on_unstable_physics():
    with _episode() as episode:
        episode.world.data.qvel[2] = math.inf
        with pytest.raises(SimulationError, match="unstable"):
            episode.world.step(0.0, 0.0, 0.1)
