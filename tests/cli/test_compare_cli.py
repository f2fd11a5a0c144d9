"""`lanekeep compare A.json B.json`: the table, the --json document, and bad input as one line
"lanekeep compare: error: ..." with exit code 2, never a traceback.

No episode runs: the bench files are written from small fake EpisodeReports summarised as
`bench --json` does (lanekeep/report/seed_summary.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from lanekeep.cli.main import main
from lanekeep.report.json_io import SCHEMA_VERSION, report_document, write_json
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")
SEEDS = (0, 1, 2, 3)
A_RMSE = [1.0, 3.0, 2.0, 4.0]


def _episode(seed: int, rmse: float) -> EpisodeReport:
    source = SourceReport(rmse, 2 * rmse, rmse, 2 * rmse, 1.0, 0.1)
    return EpisodeReport("clear_straight", seed, 1.0, 10,
                         {"fused": source, "hough:track": source}, 3.0 + rmse, 6.0 + rmse,
                         0, 0, 0.0, 0)


def _bench_file(path: Path, rmse: list[float], seeds=SEEDS, controller=None) -> str:
    overrides = {"front_detectors": None, "reference_detector": None,
                 "controller": controller, "settings": [], "weights": None}
    docs = {label: summarise(label, [_episode(s, v) for s, v in zip(seeds, rmse, strict=True)],
                             SCENARIO, overrides=overrides)
            for label in ("clear_straight", "case2_sharp_turn")}
    write_json(path, docs)
    return str(path)


@pytest.fixture
def runs(tmp_path: Path) -> tuple[str, str]:
    a = _bench_file(tmp_path / "a.json", A_RMSE)
    b = _bench_file(tmp_path / "b.json", [v - 0.5 + 0.01 * i for i, v in enumerate(A_RMSE)],
                    controller="stanley")
    return a, b


def _one_error_line(capsys, code: int, *needles: str) -> str:
    captured = capsys.readouterr()
    assert code == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("lanekeep compare: error: ")
    assert "Traceback" not in captured.err
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


def test_compare_prints_the_table_and_exits_0(runs, capsys):
    a, b = runs
    assert main(["compare", a, b]) == 0
    out = capsys.readouterr().out
    assert f"A = {a}" in out and f"B = {b}" in out
    assert "controller: (scenario file's) -> stanley" in out
    assert "fused.rmse_cm 2b 0w 0i" in out  # B lower on every seed of both labels
    assert max(len(line) for line in out.splitlines()) <= 120


def test_json_holds_every_metric_per_label_pooled_and_counted(runs, tmp_path, capsys):
    a, b = runs
    out = tmp_path / "cmp.json"
    assert main(["compare", a, b, "--json", str(out)]) == 0
    doc = json.loads(out.read_text(), parse_constant=lambda t: pytest.fail(f"not strict: {t}"))
    assert doc["schema_version"] == SCHEMA_VERSION and doc["a"] == a and doc["b"] == b
    assert doc["b_overrides"]["controller"] == "stanley"
    assert doc["a_overrides"]["controller"] is None
    entry = doc["labels"]["clear_straight"]["fused.rmse_cm"]
    assert entry["verdict"] == "better" and entry["n"] == 4
    assert entry["diff"] == pytest.approx(-0.485)
    assert doc["all"]["fused.rmse_cm"]["n"] == 8
    assert doc["counts"]["car_rms_cm"] == {"better": 2, "worse": 0, "indistinguishable": 0}
    assert set(doc["labels"]["case2_sharp_turn"]) == set(doc["better_when"])
    assert doc["notes"] == []


def test_source_and_metrics_choose_what_is_compared(runs, tmp_path, capsys):
    a, b = runs
    out = tmp_path / "cmp.json"
    assert main(["compare", a, b, "--metrics", "fused.drift_cm", "car_rms_cm",
                 "--source", "hough:track", "--json", str(out)]) == 0
    keys = list(json.loads(out.read_text())["better_when"])
    assert keys == ["fused.drift_cm", "car_rms_cm", "hough:track.rmse_cm",
                    "hough:track.max_cm", "hough:track.ade_cm", "hough:track.fde_cm",
                    "hough:track.valid_share"]
    assert "hough:track.rmse_cm" in capsys.readouterr().out


def test_a_missing_source_is_one_line(runs, capsys):
    code = main(["compare", *runs, "--source", "lanenet:track"])
    _one_error_line(capsys, code, "source 'lanenet:track' is not in")


def test_an_unknown_metric_is_one_line(runs, capsys):
    code = main(["compare", *runs, "--metrics", "fused.speed"])
    _one_error_line(capsys, code, "unknown metric 'fused.speed'")


def test_a_missing_file_is_one_line(runs, tmp_path, capsys):
    missing = str(tmp_path / "nope.json")
    code = main(["compare", runs[0], missing])
    _one_error_line(capsys, code, missing, "no such file")


def test_bad_json_is_one_line(runs, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    code = main(["compare", str(bad), runs[1]])
    _one_error_line(capsys, code, str(bad), "not JSON")


def test_a_run_report_is_not_a_bench_document(runs, tmp_path, capsys):
    report = write_json(tmp_path / "run.json", report_document(_episode(0, 1.0), SCENARIO))
    code = main(["compare", runs[0], str(report)])
    _one_error_line(capsys, code, "run.json", "not a bench --json document (schema_version 2)")


def test_runs_on_other_seeds_are_refused(runs, tmp_path, capsys):
    other = _bench_file(tmp_path / "other.json", A_RMSE, seeds=(0, 1, 2, 7))
    code = main(["compare", runs[0], other])
    _one_error_line(capsys, code, "clear_straight: the runs have different seeds")
    assert not (tmp_path / "cmp.json").exists()


def test_help_documents_the_json_keys_and_the_interval(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["compare", "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    for needle in ("labels.LABEL.METRIC", "counts.METRIC", "a_overrides", "paired Student t",
                   "lanekeep/scoring/statistics.py", "--source", "--metrics"):
        assert needle in out, needle
