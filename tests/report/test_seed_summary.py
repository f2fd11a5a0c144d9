"""A bench label over seeds (lanekeep/report/seed_summary.py): means with intervals (the
geometric mean's, on the log scale, for errors), the departure rate with its exact interval,
paired verdicts against the margins (McNemar for departures) and every seed's own report."""

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy import stats as sps

from lanekeep.report.json_io import dumps, report_from_dict
from lanekeep.report.seed_summary import summarise
from lanekeep.report.tables import interval_table, paired_table
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import CommonSteps, EpisodeReport, SourceReport

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
    s = stats.spread(fused, log_scale=True)
    assert doc["seeds"] == [0, 1, 2, 3] and doc["n"] == 4 and doc["seed"] is None
    assert doc["sources"]["fused"]["rmse_cm"] == pytest.approx(np.mean(fused))  # stays the mean
    assert doc["sources"]["fused"]["rmse_cm_sd"] == pytest.approx(np.std(fused, ddof=1))
    # an error's interval is the geometric mean's (log scale), given with KEY_gmean
    assert doc["sources"]["fused"]["rmse_cm_gmean"] == pytest.approx(sps.gmean(fused))
    lo, hi = sps.t.interval(0.95, 3, loc=np.mean(np.log(fused)), scale=sps.sem(np.log(fused)))
    assert doc["sources"]["fused"]["rmse_cm_ci95"] == pytest.approx([math.exp(lo), math.exp(hi)])
    assert doc["sources"]["fused"]["rmse_cm_ci95"] == pytest.approx(list(s.ci95))
    # a share is no error: the mean's t interval, no geometric mean
    shares = [r.sources["hough:track"].valid_share for r in REPORTS]
    track = doc["sources"]["hough:track"]
    assert "valid_share_gmean" not in track
    assert track["valid_share_ci95"] == pytest.approx(list(stats.spread(shares).ci95))
    # the car's RMS is constant here: a zero-width interval at the value
    assert doc["car_rms_cm_ci95"][0] <= doc["car_rms_cm_gmean"] <= doc["car_rms_cm_ci95"][1]
    assert doc["car_rms_cm_ci95"] == pytest.approx([3.0, 3.0])
    assert doc["sources"]["reference"]["rmse_cm"] is None  # no estimate on any seed
    assert [report_from_dict(e) for e in doc["episodes"]] == REPORTS
    json.loads(dumps(doc))  # strict JSON


def test_per_seed_rmse_intervals_never_go_below_zero():
    """Issue case 3: occlusion's fused RMSE over five seeds, two of them bad. The mean's t
    interval would reach below 0 cm; the document's (log scale) stays positive and the tables
    show the geometric mean inside it."""
    occlusion = [1.6, 1.7, 1.9, 6.7, 11.8]
    assert stats.spread(occlusion).ci95[0] < 0.0  # the old interval
    reports = [_report(s, v, v + 0.5, v + 0.3, car_rms=2 * v) for s, v in enumerate(occlusion)]
    doc = summarise("occlusion", reports, SCENARIO)
    for entry, key in ((doc["sources"]["fused"], "rmse_cm"), (doc, "car_rms_cm"),
                       (doc["sources"]["hough:track"], "rmse_cm"), (doc, "car_max_cm")):
        lo, hi = entry[f"{key}_ci95"]
        assert 0.0 < lo < entry[f"{key}_gmean"] < hi, key
    fused = doc["sources"]["fused"]
    assert fused["rmse_cm_gmean"] == pytest.approx(sps.gmean(occlusion))
    assert fused["rmse_cm"] == pytest.approx(np.mean(occlusion))
    row = next(line for line in interval_table([doc]).splitlines()
               if line.startswith("occlusion"))
    assert "3.33 [1.06, 10.45]" in row  # the geometric mean and its interval


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
    fused = [r.sources["fused"].rmse_cm for r in REPORTS]
    hough = [r.sources["hough:track"].rmse_cm for r in REPORTS]
    # on the log scale: hough's geometric mean x (ratio - 1) = gmean(fused) - gmean(hough)
    assert paired["hough:track"]["diff_cm"] == pytest.approx(sps.gmean(fused) - sps.gmean(hough))
    assert paired["hough:track"]["diff_cm"] == pytest.approx(-0.195, abs=0.001)
    assert paired["hough:track"]["ratio"] == pytest.approx(sps.gmean(np.divide(fused, hough)))
    assert paired["hough:track"]["margin"] == pytest.approx(0.1)  # rmse: max(0.1, 5%)
    assert paired["lanenet:track"]["verdict"] == "equivalent"  # +-0.02, inside 0.1
    assert paired["lanenet:track"]["common_share"] is None  # each over its own valid steps


def test_fused_vs_track_uses_the_common_steps_where_the_reports_have_them():
    """Each source's own RMSE is over its own valid steps; where a report carries the fused
    output and the track on their common steps (`fused_vs_track`), the pairs use those."""
    common = [CommonSteps(1.0 + 0.01 * s, 1.5 + 0.01 * s, 200, 0.6 + 0.1 * s) for s in range(4)]
    reports = [dataclasses.replace(r, fused_vs_track={"hough:track": c})
               for r, c in zip(REPORTS, common, strict=True)]
    paired = summarise("clear_straight", reports, SCENARIO)["paired"]["fused_vs"]
    a, b = [c.rmse_a_cm for c in common], [c.rmse_b_cm for c in common]
    assert paired["hough:track"]["diff_cm"] == pytest.approx(sps.gmean(a) - sps.gmean(b))
    assert paired["hough:track"]["verdict"] == "better"
    assert paired["hough:track"]["common_share"] == pytest.approx(np.mean([0.6, 0.7, 0.8, 0.9]))
    # the track without them: each over its own valid steps, as before
    own = summarise("clear_straight", REPORTS, SCENARIO)["paired"]["fused_vs"]["lanenet:track"]
    assert paired["lanenet:track"] == own


def test_the_mmae_loop_is_paired_with_each_model_alone():
    alone = [_report(r.seed, 1.0, 1.0, 1.0, car_rms=r.car_rms_cm + 0.5 + 0.01 * r.seed)
             for r in REPORTS]
    doc = summarise("clear_straight", REPORTS, SCENARIO, single_model={"hough": alone})
    loop = doc["paired"]["mmae_loop_vs"]["hough"]
    assert loop["car_rms_cm"]["verdict"] == "better" and loop["car_max_cm"]["verdict"] == "better"
    assert loop["car_rms_cm"]["margin"] == pytest.approx(0.2)  # the car: max(0.2, 5%)
    # departures: McNemar's exact test, one discordant seed (seed 1 departed in the loop only)
    assert loop["lane_departures"]["diff"] == pytest.approx(0.25)
    assert loop["lane_departures"]["p_worse"] == pytest.approx(
        sps.binomtest(1, 1, 0.5, alternative="greater").pvalue)
    assert loop["lane_departures"]["verdict"] == "inconclusive"
    assert loop["failed"] == loop["lane_departures"]  # no drive ended otherwise


def test_a_model_alone_that_collides_without_departing_is_counted_as_failed():
    """The MMAE loop against a model-only loop that hit a car on three of four seeds before a
    wheel crossed a line: the departures see nothing, `failed` counts them."""
    alone = [dataclasses.replace(r, lane_departures=0, completed=not r.seed,
                                 status="collision" if r.seed else "completed") for r in REPORTS]
    ours = [dataclasses.replace(r, lane_departures=0) for r in REPORTS]
    loop = summarise("clear_straight", ours, SCENARIO,
                     single_model={"hough": alone})["paired"]["mmae_loop_vs"]["hough"]
    assert loop["lane_departures"]["diff"] == 0.0
    assert loop["failed"]["diff"] == pytest.approx(-0.75)
    assert loop["failed"]["p_better"] == pytest.approx(
        sps.binomtest(3, 3, 0.5, alternative="greater").pvalue)


def test_one_seed_has_no_interval_and_no_verdict():
    doc = summarise("clear_straight", REPORTS[:1], SCENARIO)
    assert doc["seed"] == 0 and doc["sources"]["fused"]["rmse_cm_ci95"] == [None, None]
    assert {p["verdict"] for p in doc["paired"]["fused_vs"].values()} == {"too few"}
    assert doc["sources"]["fused"]["rmse_cm_gmean"] == pytest.approx(1.0)
    assert "no verdict (fewer than 3 seeds" in interval_table([doc])


def test_two_seeds_have_an_interval_but_no_verdict():
    doc = summarise("clear_straight", REPORTS[:2], SCENARIO)
    assert None not in doc["sources"]["fused"]["rmse_cm_ci95"]
    assert {p["verdict"] for p in doc["paired"]["fused_vs"].values()} == {"too few"}


def test_a_repeated_seed_is_refused():
    with pytest.raises(ValueError, match="repeats"):
        summarise("clear_straight", [REPORTS[0], REPORTS[0]], SCENARIO)


def test_tables_count_verdicts():
    doc = summarise("clear_straight", REPORTS, SCENARIO)
    text = interval_table([doc])
    assert "1 better, 0 worse, 1 equivalent (of 2;" in text and "1/4" in text
    flowing = " ".join(text.split())  # the line wraps at the table's width
    assert "0.1 better and 0.1 worse expected by chance" in flowing  # 2.5% of 2 verdicts each
    row = next(line for line in text.splitlines() if line.startswith("clear_straight"))
    assert "1b 0w 1e" in row
    assert "1b 0w 1e" in interval_table([doc], wide=True)
    paired = paired_table([doc])
    assert "fused - hough:track RMSE" in paired
    lanenet = next(line for line in paired.splitlines() if "lanenet:track" in line)
    assert lanenet.split()[-2:] == ["0.10", "equivalent"]  # the margin, then the verdict


def test_an_inconclusive_verdict_says_what_this_n_could_detect():
    noisy = [_report(s, 1.0 + d, 1.0, 1.0) for s, d in enumerate([0.5, -0.4, 0.3, -0.2])]
    doc = summarise("clear_straight", noisy, SCENARIO)
    entry = doc["paired"]["fused_vs"]["hough:track"]
    assert entry["verdict"] == "inconclusive" and entry["detectable"] > entry["margin"]
    row = next(line for line in paired_table([doc]).splitlines() if "hough:track" in line)
    assert f"inconclusive (detectable: {entry['detectable']:.2f})" in row


def test_a_wide_interval_does_not_run_into_the_next_column():
    """The compact table read "27.12 [4.35, 168.89]0b 0w 2i" for a drive that departed."""
    doc = summarise("clear_straight", REPORTS, SCENARIO)
    fused = {**doc["sources"]["fused"], "rmse_cm_gmean": 27.12, "rmse_cm_ci95": [4.35, 168.89]}
    wide = {**doc, "sources": {**doc["sources"], "fused": fused},
            "car_rms_cm_gmean": 128.6, "car_rms_cm_ci95": [15.1, 1059.4]}
    row = next(line for line in interval_table([wide]).splitlines()
               if line.startswith("clear_straight"))
    assert "27.12 [4.35, 168.89] " in row and "128.6 [15.1, 1059.4] " in row


def test_a_drive_a_collision_ended_is_counted_as_failed_and_named_in_the_table():
    """A collision can end a drive before it departs: `departed` does not count it, `failed`
    does, and the compact table names it below the rows."""
    crashed = dataclasses.replace(REPORTS[2], completed=False, status="collision",
                                  stop_reason="collision")
    doc = json.loads(dumps({"x": summarise("clear_straight", [*REPORTS[:2], crashed,
                                                               REPORTS[3]], SCENARIO)}))["x"]
    assert doc["departed_episodes"] == 1 and doc["failed_episodes"] == 2
    assert doc["failure_rate"] == 0.5
    assert doc["failure_rate_ci95"] == pytest.approx(list(stats.rate_interval(2, 4)))
    compact = interval_table([doc])
    assert "failed without a departure (not in departed): clear_straight seed 2 (collision)" \
        in " ".join(compact.split())
    header, _, row = interval_table([doc], wide=True).splitlines()[:3]
    assert header.split()[-2:] == ["failed", "passed"] and row.split()[-2] == "2/4"
    assert "failed without" not in interval_table(
        [json.loads(dumps({"y": summarise("clear_straight", REPORTS, SCENARIO)}))["y"]])
