"""The forward radar (lanekeep/sensing/radar.py) on MuJoCo's ray caster, in built worlds: a
vehicle ahead is reported at its range within the data sheet's accuracy and with the range rate
of its approach; an empty straight road reports nothing, even with the car pitched; what is
beside the field of view or beyond the reach is not reported; the first cycle reports None."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from lanekeep.core.signals import RadarReading
from lanekeep.scenario.conditions import VehicleSpec
from lanekeep.scenario.roadside import Roadside
from lanekeep.scenario.schema import ScenarioError, load_scenario, scenario_from_dict
from lanekeep.scenario.sensors import RadarConfig
from lanekeep.scenario.traffic import Traffic
from lanekeep.sensing.radar import SITE, Radar, ray_azimuths
from lanekeep.world.build import World, build

PERIOD_S = 0.1
START_S_M = 10.0  # clear_straight's start: a straight road along +x


def _world(*vehicles: VehicleSpec) -> World:
    """clear_straight with only `vehicles` in it: no roadside props, no drawn traffic."""
    scenario = load_scenario("clear_straight")
    assert scenario.start.s_m == START_S_M and scenario.road.start_heading_deg == 0.0
    conditions = dataclasses.replace(scenario.conditions, vehicles=tuple(vehicles))
    return build(dataclasses.replace(scenario, roadside=Roadside(), traffic=Traffic(),
                                     conditions=conditions))


def _radar(world: World, perfect: bool = False, seed: int = 0, **config) -> Radar:
    return Radar(world.model, RadarConfig(**config), perfect, np.random.default_rng(seed))


def _drive(world: World, radar: Radar, periods: int = 1) -> RadarReading:
    """The first cycle, then `periods` control periods coasting; the last reading."""
    assert radar.sample(world.data) is None  # no previous poses yet: no Doppler
    reading = None
    for _ in range(periods):
        world.step(0.0, 0.0, PERIOD_S)
        reading = radar.sample(world.data)
    assert reading is not None
    return reading


def _lead(world: World) -> tuple[float, float]:
    """(x of the lead's rear face, x of the radar) now, from the world's truth."""
    body = world.model.body(world.conditions.vehicles[0].name).id
    rear = world.data.xpos[body][0] - VehicleSpec().length_m / 2.0
    return float(rear), float(world.data.site(SITE).xpos[0])


@pytest.mark.parametrize(("ahead_m", "sigma_m"), [(30.0, 0.10), (150.0, 0.40)])
def test_a_vehicle_ahead_is_reported_at_its_range_within_the_sheet_s_accuracy(ahead_m, sigma_m):
    world = _world(VehicleSpec(lane=0, s_m=START_S_M + ahead_m, speed_mps=10.0))
    radar = _radar(world)
    before = _lead(world)[0]
    reading = _drive(world, radar)
    rear, radar_x = _lead(world)
    ahead = [d for d in reading.detections if abs(d.azimuth_rad) < math.radians(3.0)]
    assert len(ahead) == 1, reading
    (lead,) = ahead
    # Near scan within 70 m (+-0.10 m), far scan beyond (+-0.40 m); 4 sigma, the plate a few cm
    # proud of the body.
    assert lead.range_m == pytest.approx(rear - radar_x, abs=4 * sigma_m)
    # Approaching: the lead's speed over the period less the car's own now.
    closing = (rear - before) / PERIOD_S - world.car.speed_mps()
    assert closing < -4.0
    assert lead.range_rate_mps == pytest.approx(closing, abs=0.15)
    assert reading.mount_x_m == pytest.approx(2.4)


def test_a_perfect_radar_ranges_to_the_centimetre_and_a_faster_lead_opens():
    world = _world(VehicleSpec(lane=0, s_m=START_S_M + 30.0, speed_mps=20.0))
    radar = _radar(world, perfect=True)
    reading = _drive(world, radar, periods=3)
    rear, radar_x = _lead(world)
    nearest = reading.detections[0]
    assert nearest.range_m == pytest.approx(rear - radar_x, abs=0.05)
    assert nearest.azimuth_rad == pytest.approx(0.0, abs=math.radians(0.2))
    assert nearest.range_rate_mps > 4.0  # 20 m/s ahead of a 15 m/s car: opening


def test_an_empty_straight_road_reports_nothing_even_with_the_car_pitched():
    world = _world()
    radar = _radar(world)
    assert _drive(world, radar, periods=2).detections == ()
    # Nose 4 degrees down (hard braking pitches a car by 1-2): the level fan stays off the road.
    adr = world.model.joint("car_root").qposadr[0]
    pitch = math.radians(4.0)
    world.data.qpos[adr + 3:adr + 7] = (math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0)
    mujoco.mj_kinematics(world.model, world.data)
    world.data.time += PERIOD_S
    assert radar.sample(world.data).detections == ()


def test_vehicles_beside_the_field_of_view_or_beyond_its_reach_are_not_reported():
    beside = VehicleSpec(lane=1, s_m=START_S_M + 2.0, speed_mps=15.0)  # 3.7 m left, level
    beyond = VehicleSpec(lane=0, s_m=START_S_M + 300.0, speed_mps=15.0)  # past 250 m
    world = _world(beside, beyond)
    assert _drive(world, _radar(world, perfect=True)).detections == ()
    # The same two with a wider field of view and a longer reach are there.
    world = _world(beside, beyond)
    wide = _radar(world, perfect=True, near_half_fov_deg=60.0, far_range_m=400.0)
    assert len(_drive(world, wide).detections) == 2


def test_the_fan_is_fine_in_the_far_scan_and_reaches_as_the_sheet_says():
    azimuths, reach = ray_azimuths(RadarConfig())
    degrees = np.degrees(azimuths)
    assert degrees[0] == pytest.approx(-45.0) and degrees[-1] == pytest.approx(45.0)
    assert np.all(np.diff(degrees) > 0)
    far = np.abs(degrees) <= 9.0 + 1e-9
    assert np.allclose(np.diff(degrees[far]), 0.25) and np.all(reach[far] == 250.0)
    assert np.all(reach[~far] == 70.0)
    # No near scan: the far one alone.
    azimuths, reach = ray_azimuths(RadarConfig(near_range_m=0.0))
    assert np.degrees(np.abs(azimuths)).max() == pytest.approx(9.0) and np.all(reach == 250.0)


def test_the_noise_is_seeded_and_perfect_draws_nothing():
    readings = []
    for seed in (3, 3, 4):
        world = _world(VehicleSpec(lane=0, s_m=START_S_M + 40.0, speed_mps=10.0))
        readings.append(_drive(world, _radar(world, seed=seed)))
    assert readings[0] == readings[1] and readings[0] != readings[2]
    world = _world(VehicleSpec(lane=0, s_m=START_S_M + 40.0, speed_mps=10.0))
    rng = np.random.default_rng(5)
    state = rng.bit_generator.state
    Radar(world.model, RadarConfig(), True, rng).sample(world.data)
    assert rng.bit_generator.state == state


def test_a_radar_key_out_of_range_is_refused_naming_it():
    with pytest.raises(ScenarioError, match=r"sensors\.radar\.far_half_fov_deg"):
        scenario_from_dict({"name": "x", "description": "x",
                            "road": {"segments": [{"kind": "straight", "length_m": 100}]},
                            "sensors": {"radar": {"far_half_fov_deg": 120.0}}})


def test_the_radar_is_read_only_for_the_adaptive_cruise():
    """The cruise is the radar's only reader: without it (or in paper mode, which ignores it)
    the signals carry no radar and its rays are not cast."""
    from lanekeep.scenario.keys import with_settings
    from lanekeep.sensing.simulator import Simulator

    scenario = load_scenario("stop_and_go_truck")  # [control] acc = true
    for settings, expect in (((), True), ((("control.acc", False),), False),
                             ((("estimation.mode", "paper"),), False)):
        simulator = Simulator(with_settings(scenario, settings), render_size=(64, 36))
        try:
            assert simulator.radar_on is expect, settings
            simulator.sense()  # the first cycle has no Doppler yet: None either way
            simulator.world.step(0.0, 0.0, PERIOD_S)
            reading = simulator.sense().signals.radar
            assert (reading is not None) is expect, settings
        finally:
            simulator.close()
