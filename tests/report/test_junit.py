"""`lanekeep bench --junit FILE`: JUnit XML that validates against the common JUnit schema
(tests/data/junit.xsd), one test case per episode, failures naming the failed criteria; and the
bench's step progress bar."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from helpers import small_scenario_text
from lxml import etree  # the `test` extra's XSD validator

from lanekeep.cli.main import main
from lanekeep.report.junit import junit_tree, write_junit
from lanekeep.scoring.metrics import EpisodeReport, SourceReport, Verdict

SCHEMA = Path(__file__).parents[1] / "data" / "junit.xsd"


def _validate(path: Path):
    schema = etree.XMLSchema(etree.parse(str(SCHEMA)))
    doc = etree.parse(str(path))
    assert schema.validate(doc), schema.error_log
    return doc


def _report(name: str, status: str = "completed", verdicts=(), wall_s: float = 2.5
            ) -> EpisodeReport:
    source = SourceReport(3.0, 6.0, 4.0, 7.0, 1.0)
    return EpisodeReport(
        scenario=name, seed=0, duration_s=2.0, steps=20, sources={"fused": source,
                                                                   "reference": source},
        car_rms_cm=2.0, car_max_cm=5.0, lane_departures=0, mmae_switches=0, no_estimate_s=0.0,
        reference_repairs=0, completed=status == "completed", wall_s=wall_s,
        stop_reason="" if status == "completed" else f"{status} at t = 1.0 s", status=status,
        criteria=tuple(verdicts))


def test_the_schema_rejects_what_it_should():
    """The XSD is not vacuous: a case without a name and a suite without `tests` fail it."""
    schema = etree.XMLSchema(etree.parse(str(SCHEMA)))
    assert not schema.validate(etree.fromstring(
        b'<testsuites><testsuite name="a" tests="1"><testcase/></testsuite></testsuites>'))
    assert not schema.validate(etree.fromstring(
        b'<testsuites><testsuite name="a"><testcase name="x"/></testsuite></testsuites>'))
    assert not schema.validate(etree.fromstring(
        b'<testsuites><testsuite name="a" tests="1"><testcase name="x"><failure/><error/>'
        b'</testcase></testsuite></testsuites>'))


def test_every_outcome_validates_and_is_counted(tmp_path):
    passed = _report("ok", verdicts=[Verdict("status", "completed", "completed", True),
                                     Verdict("lane_departures", 0, 0, True)])
    failed = _report("bad", verdicts=[Verdict("status", "completed", "completed", True),
                                      Verdict("fused_rmse_m", 0.05, 0.09, False)])
    off = _report("turn", "off_road",
                  verdicts=[Verdict("status", "completed", "off_road", False)])
    broken = _report("blown", "unstable",
                     verdicts=[Verdict("status", "completed", "unstable", False)])
    reports = {"ok": passed, "bad": failed, "turn": off, "blown": broken, "never": None}
    doc = _validate(write_junit(tmp_path / "sub" / "bench.xml", reports, wall_s=12.0))
    suite = doc.getroot().find("testsuite")
    assert [c.get("name") for c in suite.findall("testcase")] == list(reports)
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors"),
            suite.get("skipped")) == ("5", "2", "1", "1")
    case = {c.get("name"): c for c in suite.findall("testcase")}
    assert case["ok"].find("failure") is None and case["ok"].find("error") is None
    assert math.isclose(float(case["ok"].get("time")), 2.5)
    assert case["bad"].find("failure").get("message") == "fused_rmse_m 0.09 > 0.05"
    assert "off_road" in case["turn"].find("failure").get("message")
    assert case["blown"].find("error").get("type") == "unstable"
    assert case["never"].find("skipped") is not None
    assert "criteria: FAIL" in case["bad"].find("system-out").text  # the episode's table
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["bench.xml"]  # no temp file


def test_an_empty_bench_is_still_a_valid_document(tmp_path):
    tree = junit_tree({}, wall_s=0.0)
    path = tmp_path / "empty.xml"
    tree.write(path, encoding="utf-8", xml_declaration=True)
    assert _validate(path).getroot().find("testsuite").get("tests") == "0"


@pytest.mark.slow
def test_bench_junit_has_one_case_per_scenario_and_exits_1_on_a_failure(tmp_path, capsys):
    """Two reduced-size scenarios: a straight that meets its criteria and the sharp turn at
    30 m/s, which leaves the road. Exit 1; one valid test case each, the turn's a failure; the
    progress (lines: stderr is no terminal here) reaches the bench's total, which the early
    end of the turn shrank."""
    straight, turn = tmp_path / "straight.toml", tmp_path / "turn.toml"
    straight.write_text(small_scenario_text("clear_straight")
                        + "\n[criteria]\nmax_lane_departures = 0\nmax_car_lateral_error_m = 0.5\n")
    turn.write_text(small_scenario_text("sharp_turn").replace(
        "target_speed_mps = 15.0", "target_speed_mps = 30.0"))
    out = tmp_path / "bench.xml"
    code = main(["bench", str(straight), str(turn), "--seconds", "8", "--workers", "1",
                 "--junit", str(out)])
    assert code == 1
    suite = _validate(out).getroot().find("testsuite")
    case = {c.get("name"): c for c in suite.findall("testcase")}
    assert list(case) == ["straight", "turn"]
    assert case["straight"].find("failure") is None
    assert case["turn"].find("failure").get("message").startswith("status off_road")
    captured = capsys.readouterr()
    assert "FAILED turn: status off_road" in captured.out
    assert "criteria: 1 of 2 scenarios passed" in captured.out
    assert "observed fail rate 1/2 = 0.500 [0.013, 0.987] (Clopper-Pearson 95%)" in captured.out
    assert f"wrote {out}" in captured.err
    last = [line for line in captured.err.splitlines() if line.startswith("bench (2 ")][-1]
    done, total = last.split(" s simulated")[0].split()[-1].split("/")
    assert done == total and float(total) < 16.0  # 2 x 8 s planned; the turn ended early
    assert "(100%), wall " in last


def test_the_step_bar_shows_elapsed_and_remaining_and_takes_a_shrinking_total(capsys):
    from lanekeep.core.progress import set_progress, step_bar

    with step_bar(100, "bench", enabled=True) as bar:
        set_progress(bar, 30, 100)
        set_progress(bar, 60, 80)  # an episode ended early: 20 steps it will never make
    assert (bar.n, bar.total) == (60, 80)
    last = capsys.readouterr().err.replace("\r", "\n").strip().splitlines()[-1]
    assert "60/80 steps" in last and "<" in last
    with step_bar(10, "quiet", enabled=False) as bar:  # --quiet, a bench worker: nothing
        bar.update(10)
    assert capsys.readouterr().err == ""


def test_without_a_terminal_progress_is_whole_lines_every_few_seconds(capsys, monkeypatch):
    """stderr is no terminal under pytest: no bar redrawn with carriage returns but a line
    per LINE_INTERVAL_S (0 here: every update) in simulated seconds, and the last on close."""
    import lanekeep.core.progress as progress

    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 0.0)
    with progress.step_bar(40, "clear_curve", step_s=0.25) as bar:
        for _ in range(4):
            progress.set_progress(bar, bar.n + 10)
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = err.splitlines()
    assert lines[0].startswith("clear_curve: 0.0/10.0 s simulated (0%), wall ")
    assert lines[1].startswith("clear_curve: 2.5/10.0 s simulated (25%), wall ")
    assert lines[1].endswith(" left") and not lines[-1].endswith(" left")
    assert lines[-1].startswith("clear_curve: 10.0/10.0 s simulated (100%), wall ")
    assert len(lines) == len(set(lines)) == 5  # the last one is not repeated on close
    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 3600.0)
    with progress.step_bar(7, "bench (2 episodes)") as bar:  # no step length: steps
        progress.set_progress(bar, 7)
    assert capsys.readouterr().err.splitlines() == [
        "bench (2 episodes): 0/7 steps (0%), wall 00:00, about ? left",
        "bench (2 episodes): 7/7 steps (100%), wall 00:00"]


def test_the_last_line_shows_a_total_that_shrank_after_its_steps_were_shown(capsys, monkeypatch):
    """A bench whose last episode ended early: every step it made was shown on a line before
    the shrunk total arrived (on a slow machine the lines fall so). The line on close shows
    where it ended, done == total, whatever the timing."""
    import lanekeep.core.progress as progress

    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 0.0)
    with progress.step_bar(16, "bench (2 episodes)") as bar:
        progress.set_progress(bar, 13)          # shown: 13/16
        progress.set_progress(bar, 13, 13)      # the turn ended early: no new step
    lines = capsys.readouterr().err.splitlines()
    assert lines[-2].startswith("bench (2 episodes): 13/16 steps (81%)")
    assert lines[-1] == "bench (2 episodes): 13/13 steps (100%), wall 00:00"
