"""Safety among other vehicles (lanekeep/scoring/safety.py): the gap and time to collision to
the vehicle ahead in the car's path, contact of oriented rectangles, hard braking events with
hysteresis; the episode's safety metrics in its report, its JSON, the bench's document and
table, `compare` on files written before them; a collision ends an episode that fails."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from helpers import small_scenario_text

from lanekeep.geometry.road import Road, SegmentSpec
from lanekeep.loop.episode import Episode
from lanekeep.report.compare import compare_runs, parse_metric
from lanekeep.report.json_io import dumps, report_document, report_from_dict
from lanekeep.report.seed_summary import summarise
from lanekeep.report.tables import safety_table
from lanekeep.scenario.schema import CriteriaConfig, load_scenario, parse_scenario
from lanekeep.scoring.criteria import failure_message, judge
from lanekeep.scoring.gate import Truth
from lanekeep.scoring.metrics import EpisodeReport, SourceReport
from lanekeep.scoring.safety import (
    G_MPS2,
    Footprint,
    HardBraking,
    SafetyTally,
    StepSafety,
    footprints_overlap,
    line_length,
    step_safety,
    vehicle_footprints,
)
from lanekeep.traffic.state import VehicleState

CAR = (4.7, 1.9)  # CarGeometry's length and width
STRAIGHT = Road([SegmentSpec("straight", 500.0)], n_lanes=2, lane_width_m=3.5)
RIGHT, LEFT = STRAIGHT.lane_center_r(0), STRAIGHT.lane_center_r(1)


def vehicle(name: str = "v1", s_m: float = 70.0, r_m: float = RIGHT, speed_mps: float = 10.0,
            direction: int = 1, lateral_speed_mps: float = 0.0, length_m: float = 4.6,
            width_m: float = 1.85) -> VehicleState:
    return VehicleState(name, s_m, r_m, speed_mps, direction, 0, length_m, width_m,
                        lateral_speed_mps=lateral_speed_mps,
                        changing_lane=lateral_speed_mps != 0.0)


def on(road: Road, s_m: float, r_m: float, speed_mps: float, vehicles, accel_mps2: float = 0.0,
       yaw_offset_rad: float = 0.0) -> StepSafety:
    """The car at Frenet (s, r) heading along the road (plus `yaw_offset_rad`)."""
    x, y = road.position(s_m, r_m)
    yaw = float(road.heading_at(s_m)) + yaw_offset_rad
    return step_safety(road, (float(x), float(y), yaw), s_m, r_m, speed_mps, CAR, accel_mps2,
                       vehicles)


# -- the vehicle ahead: gap and TTC ------------------------------------------------------------
def test_a_vehicle_20_m_ahead_closing_at_5_mps():
    step = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(s_m=70.0, speed_mps=10.0)])
    gap = 20.0 - 4.7 / 2 - 4.6 / 2  # centre to centre less both half lengths: bumper to bumper
    assert step.lead == "v1" and step.gap_m == pytest.approx(gap)
    assert step.closing_speed_mps == pytest.approx(5.0)
    assert step.ttc_s == pytest.approx(gap / 5.0)  # 3.07 s, not 20 / 5
    assert step.collided_with == "" and len(step.vehicles) == 1


def test_a_vehicle_in_the_next_lane_is_not_ahead_one_straddling_the_line_is():
    beside = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(r_m=LEFT)])
    assert beside.lead == "" and beside.gap_m is None and beside.ttc_s == math.inf
    # 1.5 m to the left: its right side (1.5 - 0.925) is inside the car's left side (0.95)
    straddling = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(r_m=RIGHT + 1.5)])
    assert straddling.lead == "v1"


def test_the_nearest_vehicle_ahead_counts_and_none_behind():
    step = on(STRAIGHT, 50.0, RIGHT, 15.0,
              [vehicle("far", s_m=90.0), vehicle("near", s_m=65.0), vehicle("behind", s_m=30.0)])
    assert step.lead == "near" and step.gap_m == pytest.approx(15.0 - 4.65)
    assert on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(s_m=30.0)]).lead == ""


def test_an_oncoming_vehicle_closes_at_the_sum_of_the_speeds():
    step = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(s_m=100.0, speed_mps=10.0, direction=-1)])
    assert step.closing_speed_mps == pytest.approx(25.0)
    assert step.ttc_s == pytest.approx((50.0 - 4.65) / 25.0)


def test_a_faster_vehicle_ahead_has_a_gap_but_no_ttc_a_parked_one_counts():
    away = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(speed_mps=20.0)])
    assert away.gap_m == pytest.approx(15.35) and away.closing_speed_mps == pytest.approx(-5.0)
    assert away.ttc_s == math.inf
    parked = on(STRAIGHT, 50.0, RIGHT, 15.0, [vehicle(speed_mps=0.0)])
    assert parked.ttc_s == pytest.approx(15.35 / 15.0)


def test_the_gap_follows_the_car_s_line_on_a_curve():
    """On a left arc of radius 50 m the right lane (r = -1.75) is longer than the centreline
    by 1.75 / 50: the gap is measured along the car's own line."""
    radius = 50.0
    road = Road([SegmentSpec("arc", 200.0, 1.0 / radius)], n_lanes=2, lane_width_m=3.5)
    assert line_length(road, 40.0, 20.0, RIGHT) == pytest.approx(20.0 * (1 + 1.75 / radius))
    step = on(road, 40.0, RIGHT, 15.0, [vehicle(s_m=60.0)])
    assert step.gap_m == pytest.approx(20.0 * (1 + 1.75 / radius) - 4.65)


def test_across_the_seam_of_a_closed_road():
    radius = 100.0
    ring = Road([SegmentSpec("arc", 2 * math.pi * radius, 1.0 / radius)], n_lanes=2,
                lane_width_m=3.5)
    assert ring.closed
    s_car = ring.length_m - 10.0
    step = on(ring, s_car, RIGHT, 15.0, [vehicle(s_m=5.0, speed_mps=10.0)])
    centres = 15.0 * (1 + 1.75 / radius)  # along the outer (right) lane of a left ring
    assert step.lead == "v1" and step.gap_m == pytest.approx(centres - 4.65, abs=1e-6)


# -- contact: oriented rectangles ------------------------------------------------------------
def test_overlapping_rectangles_collide_separate_ones_do_not():
    a = Footprint("a", 0.0, 0.0, 0.0, 4.0, 2.0)
    assert footprints_overlap(a, Footprint("b", 3.9, 0.0, 0.0, 4.0, 2.0))
    assert not footprints_overlap(a, Footprint("b", 4.1, 0.0, 0.0, 4.0, 2.0))
    assert footprints_overlap(a, Footprint("b", 0.0, 1.99, 0.0, 4.0, 2.0))  # side by side


def test_rotated_rectangles_whose_bounding_boxes_overlap_but_not_they():
    """Two 2 m squares turned 45 degrees (diamonds): touching corners are no contact, a
    millimetre more is; side by side along a diagonal their axis-aligned boxes overlap while
    they stay 12 cm apart."""
    half_diagonal = math.sqrt(2.0)

    def diamond(x: float, y: float) -> Footprint:
        return Footprint("b", x, y, math.pi / 4, 2.0, 2.0)

    a = diamond(0.0, 0.0)
    assert not footprints_overlap(a, diamond(2 * half_diagonal, 0.0))  # corner on corner
    assert footprints_overlap(a, diamond(2 * half_diagonal - 0.001, 0.0))
    assert not footprints_overlap(a, diamond(2 * half_diagonal + 0.01, 0.0))
    # edges x + y = 1.414 (a) and 1.586 (b): parallel, 0.12 m apart; the boxes
    # [-1.41, 1.41]^2 and [0.09, 2.91]^2 overlap
    assert not footprints_overlap(a, diamond(1.5, 1.5))
    assert footprints_overlap(a, diamond(1.4, 1.4))


def test_a_vehicle_changing_lane_hits_the_car_corner_first():
    """Beside the car in the next lane, turned towards it by its lane change: its front right
    corner reaches into the car although its centre line stays 2.1 m away."""
    cutting = vehicle(s_m=50.0, r_m=RIGHT + 2.1, speed_mps=15.0, lateral_speed_mps=-4.0)
    assert cutting.heading_offset_rad == pytest.approx(math.atan2(-4.0, 15.0))
    straight = dataclasses.replace(cutting, lateral_speed_mps=0.0, changing_lane=False)
    assert on(STRAIGHT, 50.0, RIGHT, 15.0, [straight]).collided_with == ""
    assert on(STRAIGHT, 50.0, RIGHT, 15.0, [cutting]).collided_with == "v1"


def test_an_oncoming_vehicle_s_footprint_points_against_the_road():
    (f,) = vehicle_footprints(STRAIGHT, [vehicle(direction=-1, lateral_speed_mps=1.0)])
    # driving towards -s and moving left (+r): turned right of its own heading, pi - a
    assert f.yaw_rad == pytest.approx(math.pi + math.atan2(-1.0, 10.0))
    assert (f.x_m, f.y_m) == pytest.approx(tuple(STRAIGHT.position(70.0, RIGHT)))


def test_a_parked_vehicle_in_the_lane_is_hit_when_the_car_reaches_it():
    parked = vehicle("parked", s_m=54.0, speed_mps=0.0)
    assert on(STRAIGHT, 50.0, RIGHT, 15.0, [parked]).collided_with == "parked"
    assert on(STRAIGHT, 49.0, RIGHT, 15.0, [parked]).collided_with == ""  # 0.35 m apart


# -- hard braking ----------------------------------------------------------------------------
def test_one_braking_is_one_event_however_it_wavers():
    tally = SafetyTally()
    assert tally.braking == HardBraking() and tally.braking.threshold_mps2 == 0.4 * G_MPS2
    # brakes hard, eases to 3 m/s^2 (above the release level) and back: one event; released
    # below 0.2 g, then a second hard braking
    for accel in (-1.0, -4.0, -4.5, -3.0, -4.0, -1.0, -5.0, -1.5, 0.5):
        tally.add(StepSafety(accel_mps2=accel))
    assert tally.hard_braking_events == 2
    without_hysteresis = sum(1 for a, b in zip([0.0, -1, -4, -4.5, -3, -4, -1, -5, -1.5],
                                               [-1, -4, -4.5, -3, -4, -1, -5, -1.5, 0.5],
                                               strict=True)
                             if -b >= 0.4 * G_MPS2 > -a)
    assert without_hysteresis == 3
    assert tally.min_ttc_s == math.inf and tally.min_gap_m is None and tally.collisions == 0


def test_the_tally_keeps_the_minima_and_counts_contact_once():
    tally = SafetyTally()
    for gap, ttc, hit in ((20.0, 4.0, ""), (12.0, math.inf, ""), (None, math.inf, ""),
                          (0.0, 0.0, "v1"), (0.0, 0.0, "v1")):
        tally.add(StepSafety(gap_m=gap, ttc_s=ttc, collided_with=hit))
    assert tally.min_gap_m == 0.0 and tally.min_ttc_s == 0.0 and tally.collisions == 1
    with pytest.raises(ValueError):
        HardBraking(threshold_mps2=2.0, release_mps2=3.0)


# -- the report, its JSON, the bench and compare ------------------------------------------------
def report(seed: int = 0, **safety) -> EpisodeReport:
    source = SourceReport(2.0, 4.0, 3.0, 5.0, 1.0, 0.1)
    return EpisodeReport("clear_straight", seed, 1.0, 10,
                         {"fused": source, "hough:track": source}, 3.0, 6.0, 0, 0, 0.0, 0,
                         **safety)


def test_a_report_carries_the_safety_metrics_through_json_and_back():
    scenario = load_scenario("clear_straight")
    never = report()
    doc = json.loads(dumps(report_document(never, scenario)))
    assert doc["min_ttc_s"] is None and doc["min_gap_m"] is None  # inf and none: null
    assert doc["hard_braking_events"] == 0 and doc["collisions"] == 0
    assert report_from_dict(doc) == never and report_from_dict(doc).min_ttc_s == math.inf
    close = report(min_ttc_s=1.2, min_gap_m=3.5, hard_braking_events=2, collisions=1,
                   completed=False, status="collision",
                   stop_reason="collision with v1 at t = 0.9 s")
    doc = json.loads(dumps(report_document(close, scenario)))
    assert (doc["min_ttc_s"], doc["min_gap_m"], doc["status"]) == (1.2, 3.5, "collision")
    assert report_from_dict(doc) == close
    old = {k: v for k, v in doc.items()
           if k not in ("min_ttc_s", "min_gap_m", "hard_braking_events", "collisions")}
    assert report_from_dict(old).min_ttc_s == math.inf  # a document from before them


def test_the_table_says_the_safety_line_below_the_car():
    lines = report(min_ttc_s=2.5, min_gap_m=8.25, hard_braking_events=1).table().splitlines()
    car = next(i for i, line in enumerate(lines) if line.startswith("car: "))
    assert lines[car + 1] == ("safety: min TTC 2.5 s, min gap 8.2 m (vehicle ahead in the "
                              "car's path); hard braking 1 (>= 0.4 g); collisions 0")
    assert "safety: no vehicle ahead in the car's path; hard braking 0" in report().table()


def test_a_collision_fails_the_episode_whatever_its_numbers():
    hit = report(collisions=1, completed=False, status="collision",
                 stop_reason="collision with v1 at t = 0.9 s")
    judged = judge(hit, CriteriaConfig())
    assert not judged.passed
    assert failure_message(judged) == "status collision (collision with v1 at t = 0.9 s)"
    assert "[STOPPED (collision): partial episode: collision with v1" in judged.table()


def bench_docs(reports_by_label: dict[str, list[EpisodeReport]]) -> dict:
    scenario = load_scenario("clear_straight")
    return json.loads(dumps({label: summarise(label, rs, scenario)
                             for label, rs in reports_by_label.items()}))


def test_the_bench_summarises_collisions_and_minima_over_seeds():
    reports = [report(0, min_ttc_s=3.0, min_gap_m=9.0, hard_braking_events=1),
               report(1, min_ttc_s=1.5, min_gap_m=12.0),
               report(2, collisions=1, min_gap_m=0.0, min_ttc_s=0.0, completed=False,
                      status="collision")]
    doc = bench_docs({"x": reports})["x"]
    assert doc["collided_episodes"] == 1 and doc["collision_rate"] == pytest.approx(1 / 3)
    assert doc["min_ttc_s"] == 0.0 and doc["min_gap_m"] == 0.0
    assert doc["hard_braking_events"] == pytest.approx(1 / 3)
    # the mean of the episodes' minima, (3 + 1.5 + 0) / 3, with its t interval over three
    assert doc["min_ttc_s_mean"] == pytest.approx(1.5) and doc["min_ttc_s_n"] == 3
    half = 4.302653 * np.std([3.0, 1.5, 0.0], ddof=1) / np.sqrt(3)  # t(0.975, 2)
    assert doc["min_ttc_s_mean_ci95"] == pytest.approx([0.0, 1.5 + half], rel=1e-4)
    assert 1.5 - half < 0.0  # the t interval's lower end, cut at zero: a TTC is never negative
    near = bench_docs({"n": [report(0, min_ttc_s=3.0), report(1, min_ttc_s=3.5)]})["n"]
    near_half = 12.706205 * np.std([3.0, 3.5], ddof=1) / np.sqrt(2)  # t(0.975, 1)
    assert 3.25 - near_half > 0.0  # an interval above zero is left as it is
    assert near["min_ttc_s_mean_ci95"] == pytest.approx([3.25 - near_half, 3.25 + near_half],
                                                        rel=1e-4)
    table = safety_table([doc])
    assert "min TTC s" in table and "1/3" in table
    assert max(len(line) for line in table.splitlines()) <= 100
    # a wide interval does not run into the column before it (it read "7.1148.5 [...")
    wide = {**doc, "min_ttc_s": 7.1, "min_ttc_s_mean": 148.5,
            "min_ttc_s_mean_ci95": [-209.3, 506.2]}
    assert "7.1 148.5 [-209.3, 506.2]" in " ".join(safety_table([wide]).split())
    quiet = bench_docs({"y": [report(0), report(1)]})["y"]
    assert quiet["min_ttc_s"] is None and quiet["min_gap_m"] is None
    assert safety_table([quiet]) == ""  # nothing to say without vehicles or braking


def _strip_safety(docs: dict) -> dict:
    """Bench documents as written before the safety metrics."""
    keys = ("min_ttc_s", "min_gap_m", "hard_braking_events", "collisions")
    for doc in docs.values():
        doc["episodes"] = [{k: v for k, v in e.items() if k not in keys}
                           for e in doc["episodes"]]
    return docs


def test_compare_takes_the_safety_metrics_by_name_and_old_files_without_them():
    seeds = range(4)
    a = bench_docs({"x": [report(s, hard_braking_events=s % 2, min_gap_m=5.0 + s) for s in seeds]})
    b = bench_docs({"x": [report(s, min_gap_m=6.0 + s) for s in seeds]})
    assert parse_metric("collisions").source is None
    assert parse_metric("min_ttc_s").lower_is_better is False
    keys = ["car_rms_cm", "collisions", "hard_braking_events", "min_gap_m", "min_ttc_s"]
    result = compare_runs(a, b, keys)
    assert result["better_when"]["min_gap_m"] == "higher"
    assert result["labels"]["x"]["min_gap_m"]["diff"] == pytest.approx(1.0)
    assert result["labels"]["x"]["min_ttc_s"]["dropped"] == 4  # never closing: no value
    assert result["labels"]["x"]["collisions"]["verdict"] == "inconclusive"
    old = compare_runs(_strip_safety(a), b, keys, a_name="old.json")
    assert list(old["better_when"]) == ["car_rms_cm"]  # the rest left out, with a note each
    assert "collisions is not in old.json (written before lanekeep reported it): not " \
           "compared" in old["notes"]
    assert compare_runs(_strip_safety(a), _strip_safety(b))["better_when"]  # the defaults


# -- a collision ends the episode ------------------------------------------------------------
def test_a_parked_vehicle_ahead_ends_the_episode_with_a_collision(monkeypatch):
    """The car drives into a vehicle parked 8 m ahead in its lane (the gate's other vehicles
    replaced by it: whatever else the world drives is not seen by scoring here): the step of
    contact is the last one scored, the report says status "collision" and names it, and
    fails."""
    scenario = parse_scenario(small_scenario_text("clear_straight", seconds=3.0),
                              "clear_straight.toml")
    road_s = {}

    def parked(self: Truth):
        if "s" not in road_s:  # where the car started, once
            s, r = self.road.local_coordinates(self.pose()[:2])
            road_s["s"], road_s["r"] = s + 4.7 / 2 + 8.0 + 4.6 / 2, r
        return (vehicle("parked_1", s_m=road_s["s"], r_m=road_s["r"], speed_mps=0.0),)

    monkeypatch.setattr(Truth, "vehicles", parked)
    results = []
    with Episode(scenario, render_size=(160, 90)) as episode:
        report = episode.run(on_step=lambda result, total: results.append(result))
    assert report.status == "collision" and not report.completed
    assert report.stop_reason.startswith("collision with parked_1 at t = ")
    assert report.collisions == 1 and report.min_gap_m == 0.0 and report.min_ttc_s == 0.0
    assert [bool(r.collision) for r in results] == [False] * (len(results) - 1) + [True]
    assert results[-1].collision in results[-1].events
    assert results[0].safety.gap_m == pytest.approx(8.0, abs=1.6)  # 15 m/s for 0.1 s
    assert not judge(report, CriteriaConfig()).passed


def test_one_episode_with_a_time_to_collision_has_no_interval_and_the_table_says_so():
    """Three seeds, one closing on a vehicle ahead: its mean has no interval (null bounds in
    the bench's strict JSON), and the safety table prints dashes instead of stopping the
    bench with a traceback after its JSON was written (seen 2026-11-30 on the tuning
    scenarios, tune_traffic_lead_van_three_lanes)."""
    reports = [report(0, min_ttc_s=2.5, min_gap_m=9.0), report(1, min_gap_m=12.0),
               report(2, min_gap_m=10.0)]
    doc = bench_docs({"x": reports})["x"]
    assert doc["min_ttc_s_mean"] == pytest.approx(2.5)
    assert doc["min_ttc_s_mean_ci95"] == [None, None]
    line = next(x for x in safety_table([doc]).splitlines() if x.startswith("x "))
    assert "2.5 [-, -]" in line
