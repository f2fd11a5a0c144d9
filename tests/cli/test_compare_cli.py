"""`lanekeep compare A.json B.json`: the table, the --json document, and bad input as one line
"lanekeep compare: error: ..." with exit code 2, never a traceback.

No episode runs: the bench files are written from small fake EpisodeReports summarised as
`bench --json` does (lanekeep/report/seed_summary.py)."""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path

import numpy as np
import pytest
from cli.error_lines import one_error_line  # tests/ is on sys.path
from scipy.stats import gmean

from lanekeep.cli.main import main
from lanekeep.report.json_io import SCHEMA_VERSION, report_document, write_json
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")
SEEDS = (0, 1, 2, 3)
A_RMSE = [1.0, 3.0, 2.0, 4.0]
B_RMSE = [0.7 * v + 0.01 * i for i, v in enumerate(A_RMSE)]


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
    # B 30% lower on every seed: errors are judged as ratios (log scale) against a margin of
    # max(0.1 cm, 5%), so a fixed 0.5 cm (the old fixture) is no longer a clear claim
    b = _bench_file(tmp_path / "b.json", B_RMSE, controller="stanley")
    return a, b


_one_error_line = partial(one_error_line, start="lanekeep compare: error: ")

def test_compare_prints_the_table_and_exits_0(runs, capsys):
    a, b = runs
    assert main(["compare", a, b]) == 0
    out = capsys.readouterr().out
    assert f"A = {a}" in out and f"B = {b}" in out
    assert "controller: (scenario file's) -> stanley" in out
    assert "fused.rmse_cm 2b 0w (Holm: 2b 0w)" in out  # B lower on every seed of both labels
    assert "fused.rmse_cm max(0.1, 5%)" in out  # the margin in force
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
    # the log scale given back in cm: gmean(B) - gmean(A)
    assert entry["diff"] == pytest.approx(gmean(B_RMSE) - gmean(A_RMSE))
    assert entry["ratio"] == pytest.approx(gmean(np.divide(B_RMSE, A_RMSE)))
    pooled = doc["all"]["fused.rmse_cm"]  # stratified: each label once, as a ratio
    assert pooled["labels"] == 2 and pooled["scale"] == "ratio"
    assert pooled["diff"] == pytest.approx(entry["ratio"])
    assert pooled["verdict"] == "too few"  # two labels: too few to pool
    assert doc["counts"]["car_rms_cm"] == {
        "better": 2, "worse": 0, "equivalent": 0, "non-inferior": 0, "non-superior": 0,
        "inconclusive": 0, "too few": 0, "better_holm": 0, "worse_holm": 0,
        "expected_by_chance": pytest.approx(0.05)}  # p_better ~2% twice: Holm keeps neither
    assert doc["margins"]["fused.rmse_cm"] == "max(0.1, 5%)"
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


def test_a_huge_margin_turns_better_into_equivalent(runs, tmp_path, capsys):
    """Issue case 7: --margin overrides the declared margin, for every label or for one."""
    a, b = runs
    out = tmp_path / "cmp.json"
    assert main(["compare", a, b, "--margin", "fused.rmse_cm=5", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    doc = json.loads(out.read_text())
    for label in ("clear_straight", "case2_sharp_turn"):
        entry = doc["labels"][label]["fused.rmse_cm"]
        assert entry["verdict"] in ("equivalent", "non-inferior") and entry["margin"] == 5.0
        assert doc["labels"][label]["car_rms_cm"]["verdict"] == "better"  # untouched
    assert doc["margins"]["fused.rmse_cm"] == "5"
    assert "fused.rmse_cm 5" in text and "fused.rmse_cm 0b 0w 2e" in text
    # a label's own override: that label only
    assert main(["compare", a, b, "--margin", "clear_straight:fused.rmse_cm=5,10%",
                 "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["labels"]["clear_straight"]["fused.rmse_cm"]["verdict"] == "equivalent"
    assert doc["labels"]["case2_sharp_turn"]["fused.rmse_cm"]["verdict"] == "better"


@pytest.mark.parametrize("bad", ["fused.rmse_cm=abc", "fused.speed=1", "fused.rmse_cm",
                                 "occlusion:car_max_cm=-1"])
def test_a_bad_margin_is_one_line(runs, capsys, bad):
    code = main(["compare", *runs, "--margin", bad])
    _one_error_line(capsys, code, f"--margin {bad!r}", "[LABEL:]METRIC=ABS[,REL%]")


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
    for needle in ("labels.LABEL.METRIC", "counts.METRIC", "a_overrides",
                   "Student t over the per-seed differences", "log ratios for",
                   "margin of practical relevance", "--margin", "McNemar", "Holm",
                   "stratified", "better_holm", "expected_by_chance", "too few",
                   "lanekeep/scoring/statistics.py", "--source", "--metrics"):
        assert needle in out, needle
