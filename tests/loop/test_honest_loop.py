"""The loop's honesty boundary: perception, estimation and control see camera frames and the
car's sensor signals only.

For the built-in car side this holds by construction: the driver is built from a
`DriverConfig` (settings and the car's spec sheet) and its packages cannot import the world,
sensing, scoring, the loop or MuJoCo (tests/project/test_layers.py). What the static rule
cannot reach is a plug-in, loaded by import path at run time: there the runtime guard
(tests/truth_guard.py) proves that it neither holds the truth nor reads it
(tests/loop/test_truth_leaks.py has a leak of each kind it must catch).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import small_scenario
from truth_guard import TruthLeak, guard_truth, path_to_truth, truth_objects

from lanekeep.core.steps import Observation
from lanekeep.detectors.base import LaneEstimate
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.loop.episode import Episode

PLUGIN = "plugins.sham:ShamHough"  # a plug-in by import path: the static rule cannot see it


def test_the_driver_is_built_from_settings_and_a_spec_sheet_only():
    """Nothing in the driver's config or the driver itself leads to a truth object, and the
    config's fields are settings, the car's dimensions and its cameras' models."""
    with Episode(small_scenario("clear_curve", 1.0), render_size=(160, 90)) as episode:
        truth = truth_objects(episode)
        config = episode.driver.config
        assert path_to_truth(config, "config", truth) is None
        assert path_to_truth(episode.driver, "driver", truth) is None
        assert {f.name for f in dataclasses.fields(config)} == {
            "estimation", "controller", "period_s", "target_speed_mps", "car", "cameras",
            "distortions", "acc", "detectors"}  # acc: the adaptive cruise's settings
        # ([control]); detectors: the scenario's [detectors] settings
        assert all(isinstance(c, CameraModel) for c in config.cameras.values())


def test_the_driver_steps_on_an_observation_alone():
    """`Driver.step` takes frames and signals and returns a command and what it believed."""
    with Episode(small_scenario("clear_straight", 1.0), render_size=(160, 90)) as episode:
        observation = episode.simulator.sense()
        command, belief = episode.driver.step(
            Observation(observation.time_s, dict(observation.frames), observation.signals))
    assert -1.0 <= command.steer <= 1.0 and -1.0 <= command.throttle <= 1.0
    assert set(belief.estimates) == {*episode.driver.front, "reference"}
    assert all(isinstance(e, LaneEstimate) for e in belief.estimates.values())
    assert np.isfinite(belief.estimate.selection.probabilities).all()


@pytest.mark.parametrize("mode", ["default", "paper"])
def test_a_plugin_runs_to_its_end_without_reading_truth(mode):
    """A plug-in front model by import path, guarded, in both modes."""
    scenario = small_scenario("case4_half_shade_straight", 2.0,
                              estimation={"mode": mode,
                                          "front_detectors": (PLUGIN, "sliding_window")})
    with Episode(scenario, render_size=(320, 180)) as episode:
        guard_truth(episode)
        report = episode.run()
    assert report.completed and report.steps == 20
    assert list(report.sources)[:2] == ["sham_hough", "sham_hough:track"]


def test_the_guard_catches_an_estimator_that_reads_the_true_pose(monkeypatch):
    with pytest.raises(TruthLeak) as caught, \
            Episode(small_scenario("clear_curve", 1.0), render_size=(320, 180)) as episode:
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
    guarded run, so a guarded run proves the loop itself reads `episode.truth` alone."""
    with Episode(small_scenario("clear_curve", 1.0), render_size=(320, 180)) as episode:
        guard_truth(episode)
        with pytest.raises(TruthLeak, match="Episode.world"):
            _ = episode.world.road.lane_width_m
        with pytest.raises(TruthLeak, match="Episode.scenario"):
            _ = episode.scenario.road
