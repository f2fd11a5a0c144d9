"""Off-road termination: the episode ends when all four wheels are off the paved surface (or
the car is beyond [criteria] off_road_distance_m from the lane centre), with status "off_road";
the steps after that are never scored and `lanekeep run` exits 1.

The user story of issue #22: sharp_turn copied with 30 m/s instead of 15 leaves the road;
before, `run` exited 0, said "completed": true and kept scoring the car 166 m away.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from helpers import small_scenario_text

from lanekeep.cli.main import main
from lanekeep.loop.episode import Episode
from lanekeep.report.json_io import report_from_dict
from lanekeep.scenario.schema import parse_scenario
from lanekeep.scoring.metrics import EpisodeReport
from lanekeep.world.parts import WorldLayout

SIZE = (320, 180)  # where the car goes does not depend on the image size much; the cost does


def _fast_turn_text() -> str:
    """sharp_turn at 30 m/s (22.5 m/s^2 on its 40 m radius: past any tyre's grip), small
    frames, without the shipped [criteria] (leaving the road fails whatever they say)."""
    text = small_scenario_text("sharp_turn")
    assert "target_speed_mps = 15.0" in text
    return text.replace("target_speed_mps = 15.0", "target_speed_mps = 30.0")


def test_the_30_mps_sharp_turn_leaves_the_road_and_stops_scoring():
    scenario = parse_scenario(_fast_turn_text(), "fast_turn.toml")
    results = []
    with Episode(scenario, render_size=SIZE) as episode:
        report = episode.run(on_step=lambda result, total: results.append(result))
        road = episode.world.road
        tyres = episode.world.data.geom_xpos[episode.scorer.tyre_geoms, :2]
        _, r = road.local_coordinates(tyres)
    assert report.status == "off_road" and not report.completed
    assert report.stop_reason.startswith("off road: all four wheels off the paved surface")
    # Metrics stop at the step the car left: it is the last step made, and scored.
    assert 0 < report.steps == len(results) < episode.total_steps
    assert [bool(res.off_road) for res in results] == [False] * (len(results) - 1) + [True]
    assert results[-1].off_road in results[-1].events
    # Where it stopped, every wheel is beyond the asphalt (lanes and shoulders) on one side.
    edge = road.boundary_r(0) - WorldLayout().shoulder_m
    assert np.all(np.asarray(r) < edge)  # a left turn taken too fast: off to the right
    assert report.car_max_cm / 100 > abs(road.lane_center_r(0) - edge)


def test_run_exits_1_with_status_off_road_in_the_json(tmp_path, capsys):
    path = tmp_path / "fast_turn.toml"
    path.write_text(_fast_turn_text())
    out = tmp_path / "report.json"
    assert main(["run", str(path), "--json", str(out)]) == 1
    doc = json.loads(out.read_text())
    assert doc["status"] == "off_road" and doc["completed"] is False and doc["passed"] is False
    assert doc["steps"] < 200  # 20 s at 0.1 s planned
    assert doc["criteria"] == [{"name": "status", "limit": "completed", "value": "off_road",
                                "passed": False}]
    printed = capsys.readouterr().out
    assert "[STOPPED (off road): partial episode: off road: all four wheels" in printed
    assert "status" in printed and "FAIL" in printed


def test_off_road_distance_ends_the_episode_before_the_wheels_leave(tmp_path):
    """A start 1.2 m left of the lane centre, with the limit at 1 m (file) and at 2 m
    (the command line's override): the first ends on its first step, the second does not."""
    text = small_scenario_text("clear_straight").replace("[start]", "[start]\noffset_m = 1.2", 1)
    path = tmp_path / "offset.toml"
    path.write_text(text + "\n[criteria]\noff_road_distance_m = 1.0\n")
    out = tmp_path / "offset.json"
    assert main(["run", str(path), "--seconds", "0.5", "--json", str(out)]) == 1
    doc = json.loads(out.read_text())
    assert doc["status"] == "off_road" and doc["steps"] == 1
    assert "off_road_distance_m = 1" in doc["stop_reason"]
    assert main(["run", str(path), "--seconds", "0.5", "--off-road-distance", "2",
                 "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["status"] == "completed" and doc["steps"] == 5


def test_a_report_from_before_status_reads_back_consistently():
    """Documents written before `status` existed carry only `completed` and `stop_reason`."""
    old = {"scenario": "x", "seed": 0, "duration_s": 1.0, "steps": 10, "sources": {},
           "car_rms_cm": 1.0, "car_max_cm": 2.0, "lane_departures": 0, "mmae_switches": 0,
           "no_estimate_s": 0.0, "reference_repairs": 0, "completed": False, "wall_s": 1.0,
           "stop_reason": "MuJoCo found the simulation unstable by t = 0.50 s"}
    assert report_from_dict(old).status == "unstable"
    assert report_from_dict({**old, "stop_reason": "interrupted"}).status == "interrupted"
    assert report_from_dict({**old, "completed": True, "stop_reason": ""}).status == "completed"


def test_status_and_completed_cannot_disagree():
    report = report_from_dict({
        "scenario": "x", "seed": 0, "duration_s": 1.0, "steps": 10, "sources": {},
        "car_rms_cm": 1.0, "car_max_cm": 2.0, "lane_departures": 0, "mmae_switches": 0,
        "no_estimate_s": 0.0, "reference_repairs": 0})
    assert report.status == "completed"
    with pytest.raises(ValueError, match="contradicts"):
        dataclasses.replace(report, status="off_road")  # completed still True
    assert isinstance(dataclasses.replace(report, completed=False, status="off_road"),
                      EpisodeReport)
