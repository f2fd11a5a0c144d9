"""The closed loop among reactive traffic: on `stop_and_go_truck` the car's adaptive cruise,
reading only its radar and its own signals, stops the car behind the truck without touching
it; with the cruise off the same drive ends in a collision with the truck, reported as such."""

from __future__ import annotations

from lanekeep.loop.episode import Episode
from lanekeep.scenario.keys import with_settings
from lanekeep.scenario.schema import load_scenario

SIZE = (160, 90)  # the radar and the traffic do not depend on the frames' size


def _drive(acc: bool, seconds: float):
    # the truck brakes at 3 s instead of 10 (a shorter drive, the same manoeuvre)
    scenario = with_settings(load_scenario("stop_and_go_truck"),
                             (("control.acc", acc), ("traffic.events[0].at_time_s", 3.0)))
    speeds = []
    with Episode(scenario, render_size=SIZE) as episode:
        report = episode.run(seconds, on_step=lambda r, _: speeds.append(r.speed_mps))
    return report, speeds


def test_the_cruise_stops_behind_the_truck_and_without_it_the_car_hits_it():
    # The truck (25 m ahead at 12 m/s) brakes at 2.5 m/s^2 from 3 s and stands from 7.8 s.
    report, speeds = _drive(True, 12.0)
    assert report.completed and report.collisions == 0, report.stop_reason
    assert min(speeds[-10:]) < 1.0  # standing, or nearly, behind the truck
    assert report.min_gap_m is not None and 2.0 < report.min_gap_m < 8.0
    blind, _ = _drive(False, 12.0)  # holds 15 m/s into a braking truck
    assert blind.status == "collision" and not blind.completed
    assert blind.stop_reason.startswith("collision with cond_vehicle_")
