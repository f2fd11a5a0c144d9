"""The per-episode streams fold in the scenario's name (lanekeep/scenario/streams.py): two
scenarios on one seed draw other start jitter, other noise and other traffic, while one
scenario on one seed repeats, in any process."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys

import numpy as np

from lanekeep.loop.episode import Episode
from lanekeep.scenario.nuisance import nuisance_summary, with_nuisance
from lanekeep.scenario.schema import load_scenario
from lanekeep.scenario.streams import name_key, stream_entropy
from lanekeep.world.traffic_flow import traffic_vehicles

RENDER = (64, 36)  # the generators are under test, not the images


def _seeded(name: str, seed: int, rename: str | None = None):
    scenario = dataclasses.replace(load_scenario(name), seed=seed)
    return scenario if rename is None else dataclasses.replace(scenario, name=rename)


def test_the_name_key_is_stable_32_bits_whatever_the_hash_seed():
    # Pinned: SHA-256 of the name, not Python's salted hash(); a change here moves every draw.
    assert name_key("occlusion") == 0xFA3CAEFB
    assert 0 <= name_key("clear_curve") < 2**32 and name_key("a") != name_key("b")
    code = "from lanekeep.scenario.streams import name_key; print(name_key('occlusion'))"
    for hash_seed in ("1", "2"):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed}
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True).stdout
        assert int(out) == 0xFA3CAEFB
    scenario = _seeded("occlusion", 7)
    assert stream_entropy(scenario, 5) == [7, 0xFA3CAEFB, 5]


def test_two_scenarios_on_one_seed_draw_other_start_jitter():
    # the same file under another name: only the name differs, and so does the drawn start
    same = nuisance_summary(_seeded("clear_curve", 7))
    renamed = nuisance_summary(_seeded("clear_curve", 7, rename="clear_curve_b"))
    assert all(same[k] != renamed[k] for k in same)
    # two shipped files with the same half-widths, on the same drawn seed
    curve, bend = load_scenario("clear_curve"), load_scenario("s_bend")
    assert curve.start.jitter == bend.start.jitter
    assert nuisance_summary(_seeded("clear_curve", 7)) != nuisance_summary(_seeded("s_bend", 7))
    # and one scenario on one seed repeats
    assert with_nuisance(_seeded("clear_curve", 7)) == with_nuisance(_seeded("clear_curve", 7))


def test_two_scenarios_on_one_seed_draw_other_traffic():
    scenario = _seeded("case1_building_shadows", 5)
    road = scenario.build_road()
    assert traffic_vehicles(scenario, road) == traffic_vehicles(scenario, road)
    renamed = dataclasses.replace(scenario, name="case1_b")
    assert traffic_vehicles(renamed, road) != traffic_vehicles(scenario, road)


def _streams(scenario) -> tuple[np.ndarray, tuple[float, float]]:
    """The episode generator's next draws (effects, particles, camera noise) and the sensors'
    per-episode draws (their own stream, spawned from it)."""
    with Episode(scenario, render_size=RENDER) as episode:
        car_sensors = episode.simulator.sensors
        sensors = (car_sensors.speed_scale, car_sensors.initial_gyro_bias_rps)
        return episode.simulator.rng.random(4), sensors


def test_two_scenarios_on_one_seed_draw_other_noise_and_one_repeats():
    scenario = _seeded("clear_straight", 5)
    first, first_sensors = _streams(scenario)
    again, again_sensors = _streams(scenario)
    other, other_sensors = _streams(dataclasses.replace(scenario, name="clear_straight_b"))
    assert np.array_equal(first, again) and first_sensors == again_sensors
    assert not np.any(first == other)
    assert first_sensors[0] != other_sensors[0] and first_sensors[1] != other_sensors[1]
    # The sensors keep their own stream: perfect sensors draw nothing from it, and the
    # episode's stream (the frames' effects) is the same (docs/reproducibility.md).
    perfect = dataclasses.replace(scenario, sensors=dataclasses.replace(scenario.sensors,
                                                                        perfect=True))
    perfect_draws, perfect_sensors = _streams(perfect)
    assert np.array_equal(perfect_draws, first) and perfect_sensors == (1.0, 0.0)
