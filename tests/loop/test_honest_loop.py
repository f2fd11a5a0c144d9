"""The loop's honesty boundary: perception, estimation and control see camera frames and the
car's sensor signals only. The simulator's truth (the road, the car's true state, the
scenario's road description) may be read to score, to record, by the sensors themselves, to
image the scene and by the simulator; any other read raises `TruthLeak` here.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from truth_guard import TruthLeak, guard_truth

from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario


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
