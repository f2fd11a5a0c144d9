"""Pass/fail criteria: `[criteria]` in a scenario and `run` / `bench` options; exit 0 when all
are met, 1 when one is not, 2 for a bad value or key (one line); the report's table and JSON
name each criterion with its limit, value and verdict."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from helpers import small_scenario_text

from lanekeep.cli.main import main
from lanekeep.loop.runner import BenchJob
from lanekeep.report.json_io import report_document, report_from_dict
from lanekeep.report.tables import bench_verdict, single_model_table, summary_table
from lanekeep.scenario.schema import CriteriaConfig, load_scenario, shipped_scenarios
from lanekeep.scoring.criteria import evaluate, failure_message, judge
from lanekeep.scoring.metrics import EpisodeReport, SourceReport


def _report(fused_rmse_cm: float = 4.0, departures: int = 0, car_max_cm: float = 20.0,
            status: str = "completed", scenario: str = "s") -> EpisodeReport:
    fused = SourceReport(fused_rmse_cm, 9.0, 5.0, 8.0, 1.0 if math.isfinite(fused_rmse_cm)
                         else 0.0)
    return EpisodeReport(
        scenario=scenario, seed=0, duration_s=10.0, steps=100,
        sources={"hough": fused, "hough:track": fused, "fused": fused, "reference": fused},
        car_rms_cm=car_max_cm / 2, car_max_cm=car_max_cm, lane_departures=departures,
        mmae_switches=0, no_estimate_s=0.0, reference_repairs=0,
        completed=status == "completed", status=status,
        stop_reason="" if status == "completed" else "off road: all four wheels off")


LIMITS = CriteriaConfig(max_lane_departures=0, max_car_lateral_error_m=0.25,
                        max_fused_rmse_m=0.05)


def _by_name(verdicts) -> dict:
    return {v.name: v for v in verdicts}


def test_a_report_within_every_limit_passes():
    verdicts = _by_name(evaluate(_report(), LIMITS))
    assert list(verdicts) == ["status", "lane_departures", "car_lateral_error_m",
                              "fused_rmse_m"]
    assert all(v.passed for v in verdicts.values())
    assert verdicts["car_lateral_error_m"].value == pytest.approx(0.20)
    assert verdicts["fused_rmse_m"].value == pytest.approx(0.04)


@pytest.mark.parametrize(("report", "failed"), [
    (_report(departures=1), {"lane_departures"}),
    (_report(car_max_cm=25.1), {"car_lateral_error_m"}),
    (_report(fused_rmse_cm=5.5), {"fused_rmse_m"}),
    (_report(fused_rmse_cm=math.nan), {"fused_rmse_m"}),  # no valid estimate at all
    (_report(status="off_road"), {"status"}),  # leaving the road fails whatever the numbers
    (_report(departures=2, fused_rmse_cm=6.0), {"lane_departures", "fused_rmse_m"}),
])
def test_each_limit_fails_on_its_own(report, failed):
    judged = judge(report, LIMITS)
    assert {v.name for v in judged.failed_criteria()} == failed and not judged.passed


def test_a_limit_at_its_value_passes_and_none_is_not_checked():
    assert judge(_report(car_max_cm=25.0), LIMITS).passed
    only_status = evaluate(_report(departures=7, fused_rmse_cm=90.0), CriteriaConfig())
    assert [v.name for v in only_status] == ["status"] and only_status[0].passed


def test_failure_message_names_each_failed_criterion_with_value_and_limit():
    report = judge(_report(departures=2, fused_rmse_cm=math.nan), LIMITS)
    assert failure_message(report) == "lane_departures 2 > 0; fused_rmse_m none > 0.05"
    off = judge(_report(status="off_road"), LIMITS)
    assert failure_message(off) == "status off_road (off road: all four wheels off)"


def test_verdicts_survive_the_json_round_trip():
    report = judge(_report(departures=1), LIMITS)
    doc = json.loads(json.dumps(report_document(report, load_scenario("clear_straight"))))
    assert doc["passed"] is False
    assert doc["criteria"][1] == {"name": "lane_departures", "limit": 0, "value": 1,
                                  "passed": False}
    assert report_from_dict(doc) == report


def test_the_table_names_each_criterion_with_value_and_verdict():
    lines = judge(_report(fused_rmse_cm=5.5), LIMITS).table().splitlines()
    assert "criteria: FAIL" in lines
    row = next(line for line in lines if line.strip().startswith("fused_rmse_m"))
    assert "0.055" in row and "<= 0.05" in row and row.endswith("FAIL")


def test_summary_tables_never_cut_a_name():
    long = "a_scenario_whose_name_is_longer_than_the_column"
    report = _report(scenario=long)
    sources = {"a_detector_with_a_long_name": report.sources["hough"],
               "a_detector_with_a_long_name:track": report.sources["hough"],
               "fused": report.sources["fused"], "reference": report.sources["reference"]}
    report = judge(EpisodeReport(**{**report.__dict__, "sources": sources}), LIMITS)
    table = summary_table([report])  # compact: the best track only
    assert long in table and table.count("a_detector_with_a_long_name") == 1
    assert table.splitlines()[2].endswith("pass")
    table = summary_table([report], wide=True)  # and the best raw detection
    assert long in table and table.count("a_detector_with_a_long_name") == 2
    assert table.splitlines()[2].endswith("pass")
    jobs = [BenchJob(long), BenchJob(long, front_detectors=("a_detector_with_a_long_name",))]
    table = single_model_table(jobs, {job.label: report for job in jobs})
    assert long in table and "a_detector_with_a_long_name only" in table


def test_every_shipped_scenario_states_the_acceptance_requirements():
    """The same stated requirements everywhere, not limits fitted to this loop (each file's
    comment says so and links the reasoning): no departure, the car within 0.5 m of the lane
    centre, the fused lane within 10 cm RMS. Before 2026-11-28 the fused limit was a
    prediction bound over five tuning seeds (tools/calibrate_criteria.py), 0.7-3.0 cm."""
    for name in shipped_scenarios():
        scenario = load_scenario(name)
        c = scenario.criteria
        assert c.max_lane_departures == 0 and c.max_car_lateral_error_m == 0.5, name
        assert c.max_fused_rmse_m == 0.10, name
        text = Path(scenario.source).read_text()
        assert "docs/statistics.md#acceptance" in text and "not fitted" in text, name


def test_a_run_cut_short_is_not_judged_by_the_files_fused_rmse_limit():
    """A limit calibrated on whole episodes says nothing of the first seconds, where the
    trackers settle: a run shorter than its scenario skips the file's fused RMSE limit, and
    judges one given on the command line."""
    from lanekeep.scoring.criteria import for_run

    config = CriteriaConfig(max_lane_departures=0, max_fused_rmse_m=0.01)
    assert for_run(config, None, full_length=True).max_fused_rmse_m == 0.01
    assert for_run(config, None, full_length=False).max_fused_rmse_m is None
    assert for_run(config, None, full_length=False).max_lane_departures == 0
    given = {"max_fused_rmse_m": 0.2}
    assert for_run(config, given, full_length=False).max_fused_rmse_m == 0.2


def _small_straight(tmp_path: Path, criteria: str) -> Path:
    path = tmp_path / "straight.toml"
    path.write_text(small_scenario_text("clear_straight") + "\n[criteria]\n" + criteria)
    return path


def test_a_passing_scenario_exits_0_and_an_override_makes_it_fail(tmp_path, capsys):
    # At 320 x 180 the detections are coarser than at the shipped 1280 x 720; the limits
    # here are the shipped ones but for the fused RMSE (measured 9.6 cm over these 3 s).
    # The run is the scenario's whole length, so the file's fused RMSE limit is judged.
    path = _small_straight(tmp_path, "max_lane_departures = 0\nmax_car_lateral_error_m = 0.5\n"
                                     "max_fused_rmse_m = 0.2\n")
    path.write_text(path.read_text().replace("duration_s = 20.0", "duration_s = 3.0", 1))
    assert load_scenario(path).duration_s == 3.0
    out = tmp_path / "run.json"
    assert main(["run", str(path), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["passed"] is True and doc["status"] == "completed"
    assert [v["name"] for v in doc["criteria"]] == ["status", "lane_departures",
                                                     "car_lateral_error_m", "fused_rmse_m"]
    captured = capsys.readouterr()
    assert "criteria: PASS" in captured.out
    # stderr is no terminal here: progress lines, not a bar redrawn with carriage returns
    assert "steps [" not in captured.err and "\r" not in captured.err
    assert "s simulated (100%)" in captured.err
    assert main(["run", str(path), "--seconds", "3", "--json", str(out),
                 "--max-fused-rmse", "0.001"]) == 1
    doc = json.loads(out.read_text())
    fused = next(v for v in doc["criteria"] if v["name"] == "fused_rmse_m")
    assert fused["limit"] == 0.001 and fused["passed"] is False and fused["value"] > 0.001
    assert "criteria: FAIL" in capsys.readouterr().out


def _one_line(capsys, code: int, *needles: str) -> None:
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err and all(n in err for n in needles), err


@pytest.mark.parametrize(("criteria", "key"), [
    ("max_fused_rmse_m = -0.1\n", "criteria.max_fused_rmse_m"),
    ("max_lane_departures = -1\n", "criteria.max_lane_departures"),
    ("max_lane_departures = 0.5\n", "criteria.max_lane_departures"),  # not an integer
    ("off_road_distance_m = 0\n", "criteria.off_road_distance_m"),
    ("max_car_lateral_error_m = 'wide'\n", "criteria.max_car_lateral_error_m"),
    ("max_departures = 0\n", "criteria.max_departures"),  # unknown key, named
])
def test_a_bad_criteria_table_is_one_line_exit_2(tmp_path, capsys, criteria, key):
    path = _small_straight(tmp_path, criteria)
    code = main(["run", str(path), "--seconds", "0.3", "--json", str(tmp_path / "o.json")])
    _one_line(capsys, code, key, "straight.toml")
    assert not (tmp_path / "o.json").exists()


@pytest.mark.parametrize(("command", "option", "value"), [
    ("run", "--max-departures", "-1"),
    ("run", "--max-lateral-error", "0"),
    ("bench", "--max-fused-rmse", "nan"),
    ("bench", "--off-road-distance", "-2"),
])
def test_a_bad_criteria_option_is_one_line_exit_2(tmp_path, capsys, command, option, value):
    code = main([command, "clear_straight", "--seconds", "0.3", option, value,
                 "--json", str(tmp_path / "o.json")])
    _one_line(capsys, code, option, value)
    assert not (tmp_path / "o.json").exists()


def test_a_failing_model_only_loop_is_reported_but_not_counted_in_the_exit_code():
    """`bench --single-model`: the scenario as configured decides the exit code; a detector
    driving alone that fails its limits is named, not counted."""
    good = judge(_report(), LIMITS)
    bad = judge(_report(car_max_cm=96.0), LIMITS)
    lines, code = bench_verdict({"s": good, "s@hough": bad}, ["s"])
    assert code == 0
    assert lines[0].startswith("FAILED s@hough: ")
    assert "criteria: 1 of 1 scenarios passed" in lines
    assert "model-only loops: 0 of 1 passed (not counted in the exit code)" in lines
    lines, code = bench_verdict({"s": bad, "s@hough": good}, ["s"])
    assert code == 1 and "criteria: 0 of 1 scenarios passed" in lines
