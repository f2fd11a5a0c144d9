"""The loop's honesty boundary: perception, estimation and control see camera frames and the
car's sensor signals only. The simulator's truth sits behind one gate (`episode.truth`) that
only scoring, recording, the sensors and the renderer are handed; tests/truth_guard.py proves
that the car side neither holds it nor reads it, in both modes, with no exemption for who is
up the stack.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from truth_guard import TruthLeak, guard_truth

from lanekeep.loop.episode import Episode
from lanekeep.loop.paper_mode import with_mode
from lanekeep.scenario.schema import load_scenario


def _short(name: str, seconds: float, mode: str | None = None):
    scenario = with_mode(load_scenario(name), mode)
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


def test_the_paper_loop_runs_to_its_end_without_reading_truth():
    """`--mode paper`: its two models, its selection, its PID, all without the gate."""
    scenario = _short("case4_half_shade_straight", 2.0, mode="paper")
    with Episode(scenario, render_size=(320, 180)) as episode:
        assert episode.driver.config.estimation.mode == "paper"
        guard_truth(episode)
        report = episode.run()
    assert report.completed and report.steps == 20
    assert list(report.sources)[:4] == ["hough", "hough:track", "sliding_window",
                                        "sliding_window:track"]


def test_the_guard_catches_an_estimator_that_reads_the_true_pose(monkeypatch):
    with pytest.raises(TruthLeak) as caught, \
            Episode(_short("clear_curve", 1.0), render_size=(320, 180)) as episode:
        car = episode.truth.car  # handed to the estimator: what the old loop did for alignment
        guard_truth(episode)
        update = episode.driver.estimator.update

        def leaky_update(detections, reference, ego, lap):
            car.pose()
            return update(detections, reference, ego, lap=lap)

        monkeypatch.setattr(episode.driver.estimator, "update", leaky_update)
        episode.step()
    # read while the estimator ran, and, when the episode closed, found held by it
    assert "Car.pose read while estimator" in str(caught.value)
    assert "estimator -> " in str(caught.value) and "-> the car" in str(caught.value)


def test_the_loop_reads_the_truth_through_its_gate_only():
    """The faces' and tools' doors (`episode.world`, `episode.scenario`) are shut in a
    guarded run, so the run above proves the loop itself reads `episode.truth` alone."""
    with Episode(_short("clear_curve", 1.0), render_size=(320, 180)) as episode:
        guard_truth(episode)
        with pytest.raises(TruthLeak, match="Episode.world"):
            _ = episode.world.road.lane_width_m
        with pytest.raises(TruthLeak, match="Episode.scenario"):
            _ = episode.scenario.road
