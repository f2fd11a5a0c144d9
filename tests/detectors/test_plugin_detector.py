"""Adding a detector is one module (tests/plugins/straight_ahead.py) plus one config table:
the registry makes it by name, its table configures it strictly, and the loop runs it."""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import plugins.straight_ahead  # noqa: F401 - registers "straight_ahead" (tests/ is on sys.path)
import pytest
from helpers import small_scenario
from plugins.straight_ahead import StraightAheadDetector

from lanekeep.core.config_io import ConfigError
from lanekeep.detectors.base import Detector
from lanekeep.detectors.config import load_config
from lanekeep.detectors.registry import DETECTORS, known_detectors, make_detector
from lanekeep.geometry.camera_model import CameraModel

K = np.array([[369.29, 0.0, 639.5], [0.0, 369.29, 359.5], [0.0, 0.0, 1.0]])
FRONT = CameraModel.from_mounting("front", K, 1280, 720, 1.5, math.radians(10.0), x_m=1.0)


def _config_file(tmp_path, table: str):
    shipped = resources.files("lanekeep.detectors").joinpath("detectors.toml").read_text()
    path = tmp_path / "detectors.toml"
    path.write_text(shipped + "\n[straight_ahead]\n" + table)
    return path


def test_it_is_known_by_name_and_meets_the_protocol():
    assert "straight_ahead" in known_detectors()
    detector = make_detector("straight_ahead", FRONT)
    assert isinstance(detector, Detector)
    estimate = detector.detect(np.zeros((720, 1280, 3), np.uint8))
    assert estimate.valid and estimate.x_m == 5.0


def test_its_table_configures_it(tmp_path):
    config = load_config(_config_file(tmp_path, "lane_width_m = 3.5\nx_ref_m = 6.0\n"))
    detector = make_detector("straight_ahead", FRONT, config)
    estimate = detector.detect(np.zeros((720, 1280, 3), np.uint8))
    assert estimate.x_m == 6.0
    np.testing.assert_allclose(estimate.left - estimate.right, [3.5, 0.0, 0.0])


def test_a_wrong_key_in_its_table_names_itself(tmp_path):
    config = load_config(_config_file(tmp_path, "lane_widht_m = 3.5\n"))
    with pytest.raises(ConfigError, match="straight_ahead.lane_widht_m"):
        make_detector("straight_ahead", FRONT, config)


def test_the_closed_loop_runs_it_as_a_front_model():
    from lanekeep.loop.episode import Episode

    scenario = small_scenario("clear_straight",
                              estimation={"front_detectors": ("hough", "straight_ahead")})
    with Episode(scenario, render_size=(640, 360)) as episode:
        report = episode.run(seconds=1.0)
    assert "straight_ahead" in report.sources
    assert report.sources["straight_ahead"].valid_share == 1.0


class _MotionLog(StraightAheadDetector):
    """Straight ahead, and a log of what the driver tells it: ("move", speed, yaw rate, dt)
    and ("detect",) in the order they come."""

    calls: list[tuple] = []

    def move(self, speed_mps, yaw_rate_rps, dt_s, lateral_speed_mps=0.0) -> None:
        self.calls.append(("move", speed_mps, yaw_rate_rps, dt_s))

    def detect(self, frame):
        self.calls.append(("detect",))
        return super().detect(frame)


def test_a_detector_with_move_is_told_the_cars_motion_before_each_frame(monkeypatch):
    """detectors/base.py: a detector that carries points between frames defines `move`; the
    driver calls it once a period, before the frame, with the odometry's speed, yaw rate and
    the period (the car's own sensors)."""
    from lanekeep.loop.episode import Episode

    monkeypatch.setitem(DETECTORS, "motion_log", _MotionLog)  # known for this test only
    _MotionLog.calls = []
    scenario = small_scenario("clear_straight",
                              estimation={"front_detectors": ("hough", "motion_log")})
    with Episode(scenario, render_size=(320, 180)) as episode:
        episode.run(seconds=1.0)
    calls = _MotionLog.calls
    assert [c[0] for c in calls] == ["move", "detect"] * 10
    moves = [c for c in calls if c[0] == "move"]
    assert all(c[3] == scenario.control_period_s for c in moves)
    assert moves[-1][1] > 1.0  # the car is moving: its wheel speed, m/s
