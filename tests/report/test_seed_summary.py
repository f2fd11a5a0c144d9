"""A bench label over seeds (lanekeep/report/seed_summary.py): means with intervals, the
departure rate with its exact interval, paired verdicts and every seed's own report."""

import json
import math

import pytest

from lanekeep.report.json_io import dumps, report_from_dict
from lanekeep.report.seed_summary import summarise
from lanekeep.report.tables import interval_table, paired_table
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")


def _report(seed: int, fused: float, hough: float, lanenet: float, departures: int = 0,
            car_rms: float = 3.0) -> EpisodeReport:
    src = {"hough": SourceReport(hough + 0.2, 3.0, 1.0, 2.0, 1.0),
           "hough:track": SourceReport(hough, 2.0, 1.0, 2.0, 1.0, 0.3),
           "lanenet:track": SourceReport(lanenet, 2.0, 1.0, 2.0, 1.0, math.nan),
           "fused": SourceReport(fused, 2.5, 1.1, 2.1, 1.0, 0.2),
           "reference": SourceReport(math.nan, math.nan, math.nan, math.nan, 0.0)}
    return EpisodeReport(scenario="clear_straight", seed=seed, duration_s=30.0, steps=300,
                         sources=src, car_rms_cm=car_rms, car_max_cm=3 * car_rms,
                         lane_departures=departures, mmae_switches=2, no_estimate_s=0.0,
                         reference_repairs=1, wall_s=10.0)


REPORTS = [_report(0, 1.00, 1.20, 1.01), _report(1, 1.10, 1.35, 1.09, departures=1),
           _report(2, 0.90, 1.05, 0.92), _report(3, 1.30, 1.48, 1.28)]


def test_means_intervals_and_every_episode_are_kept():
    doc = summarise("clear_straight", REPORTS, SCENARIO)
    fused = [r.sources["fused"].rmse_cm for r in REPORTS]
    s = stats.spread(fused)
    assert doc["seeds"] == [0, 1, 2, 3] and doc["n"] == 4 and doc["seed"] is None
    assert doc["sources"]["fused"]["rmse_cm"] == pytest.approx(s.mean)  # stays the mean
    assert doc["sources"]["fused"]["rmse_cm_ci95"] == pytest.approx(list(s.ci95))
    assert doc["sources"]["fused"]["rmse_cm_sd"] == pytest.approx(s.sd)
    assert doc["car_rms_cm_ci95"][0] <= doc["car_rms_cm"] <= doc["car_rms_cm_ci95"][1]
    assert doc["sources"]["reference"]["rmse_cm"] is None  # no estimate on any seed
    assert [report_from_dict(e) for e in doc["episodes"]] == REPORTS
    json.loads(dumps(doc))  # strict JSON


def test_departures_are_a_rate_with_an_exact_interval():
    doc = summarise("clear_straight", REPORTS, SCENARIO)
    assert doc["departed_episodes"] == 1 and doc["departure_rate"] == 0.25
    assert doc["departure_rate_ci95"] == pytest.approx(list(stats.rate_interval(1, 4)))
    none = summarise("clear_straight", [_report(s, 1, 1, 1) for s in range(10)], SCENARIO)
    assert none["departure_rate"] == 0 and none["departure_rate_ci95"][1] > 0.3  # not never


def test_fused_is_paired_with_each_models_own_track():
    paired = summarise("clear_straight", REPORTS, SCENARIO)["paired"]["fused_vs"]
    assert set(paired) == {"hough:track", "lanenet:track"}
    assert paired["hough:track"]["verdict"] == "better"  # lower by 0.15-0.25 on every seed
    assert paired["hough:track"]["diff_cm"] == pytest.approx(-0.195)
    assert paired["lanenet:track"]["verdict"] == "indistinguishable"  # +-0.02


def test_the_mmae_loop_is_paired_with_each_model_alone():
    alone = [_report(r.seed, 1.0, 1.0, 1.0, car_rms=r.car_rms_cm + 0.5 + 0.01 * r.seed)
             for r in REPORTS]
    doc = summarise("clear_straight", REPORTS, SCENARIO, single_model={"hough": alone})
    loop = doc["paired"]["mmae_loop_vs"]["hough"]
    assert loop["car_rms_cm"]["verdict"] == "better"
    assert loop["lane_departures"]["diff"] == pytest.approx(0.25)


def test_one_seed_has_no_interval_and_no_verdict():
    doc = summarise("clear_straight", REPORTS[:1], SCENARIO)
    assert doc["seed"] == 0 and doc["sources"]["fused"]["rmse_cm_ci95"] == [None, None]
    assert {p["verdict"] for p in doc["paired"]["fused_vs"].values()} == {"indistinguishable"}


def test_a_repeated_seed_is_refused():
    with pytest.raises(ValueError, match="repeats"):
        summarise("clear_straight", [REPORTS[0], REPORTS[0]], SCENARIO)


def test_tables_count_verdicts():
    doc = summarise("clear_straight", REPORTS, SCENARIO)
    text = interval_table([doc])
    assert "1 better, 0 worse, 1 indistinguishable" in text and "1/4" in text
    assert "fused - hough:track RMSE" in paired_table([doc])
