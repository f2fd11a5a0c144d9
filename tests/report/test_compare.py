"""Two bench runs paired per scenario and seed (lanekeep/report/compare.py): B - A with its
paired 95% interval and the verdict for B, refusals when the runs cannot be paired.

No episode runs: the bench documents are built by seed_summary.summarise from small fake
EpisodeReports, then passed through strict JSON as `bench --json` writes them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from lanekeep.report.compare import (
    DEFAULT_METRICS,
    WIDTH,
    IncomparableRuns,
    compare_document,
    compare_runs,
    compare_table,
    metric_set,
    parse_metric,
)
from lanekeep.report.json_io import SCHEMA_VERSION, dumps, report_document
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")
SEEDS = (0, 1, 2, 3, 4)
NAN = math.nan


def episode(seed: int, rmse: float, car: float = 5.0, departures: int = 0,
            valid: float = 1.0, status: str = "completed") -> EpisodeReport:
    """A fake episode: fused RMSE `rmse` (max, ADE, FDE derived from it), a track source."""
    fused = SourceReport(rmse, 2 * rmse, 1.5 * rmse, 3 * rmse, valid, 0.1)
    track = SourceReport(rmse + 1.0, 2 * rmse + 1.0, 1.5 * rmse, 3 * rmse, 0.9, 0.2)
    return EpisodeReport("clear_straight", seed, 1.0, 10, {"fused": fused, "hough:track": track},
                         car, 2 * car, departures, 0, 0.0, 0,
                         completed=status == "completed", status=status)


def bench(runs: dict[str, list[EpisodeReport]], controller: str | None = None) -> dict:
    """A bench --json document as read back from its file."""
    overrides = {"front_detectors": None, "reference_detector": None,
                 "controller": controller, "settings": [], "weights": None}
    docs = {label: summarise(label, reports, SCENARIO, overrides=overrides)
            for label, reports in runs.items()}
    return json.loads(dumps(docs))


def rmse_run(values: dict[str, list[float]], **kw) -> dict:
    """Labels whose seeds SEEDS have these fused RMSEs."""
    return bench({label: [episode(s, v) for s, v in zip(SEEDS, vs, strict=True)]
                  for label, vs in values.items()}, **kw)


# Seeds differ a lot (the drive), B is 0.1 cm lower on every one: only pairing sees it.
A_VALUES = [1.0, 3.0, 5.0, 2.0, 4.0]
B_LOWER = [v - 0.1 + d for v, d in zip(A_VALUES, [0.01, -0.01, 0.0, 0.02, -0.02],
                                       strict=True)]


def test_b_lower_on_every_seed_is_better_though_the_seeds_spread_far_more():
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}))
    entry = result["labels"]["x"]["fused.rmse_cm"]
    diffs = np.subtract(B_LOWER, A_VALUES)
    assert entry["verdict"] == "better" and entry["n"] == 5
    assert entry["diff"] == pytest.approx(diffs.mean())
    assert entry["diff"] == pytest.approx(entry["b_mean"] - entry["a_mean"])
    assert entry["a_mean"] == pytest.approx(np.mean(A_VALUES))
    lo, hi = entry["ci95"]
    assert lo < entry["diff"] < hi < 0.0
    # unpaired, the two runs' 95% intervals overlap almost entirely
    assert np.std(A_VALUES) > 10 * abs(entry["diff"])


def test_b_higher_is_worse_and_the_verdict_is_about_b():
    result = compare_runs(rmse_run({"x": B_LOWER}), rmse_run({"x": A_VALUES}))
    entry = result["labels"]["x"]["fused.rmse_cm"]
    assert entry["verdict"] == "worse" and entry["diff"] > 0


def test_valid_share_is_higher_better():
    a = bench({"x": [episode(s, 1.0, valid=0.8 + 0.01 * s) for s in SEEDS]})
    b = bench({"x": [episode(s, 1.0, valid=0.9 + 0.01 * s + 0.001 * (s % 2)) for s in SEEDS]})
    entry = compare_runs(a, b)["labels"]["x"]["fused.valid_share"]
    assert entry["diff"] > 0 and entry["verdict"] == "better"


def test_noise_either_way_is_indistinguishable():
    noisy = [v + d for v, d in zip(A_VALUES, [0.5, -0.6, 0.4, -0.3, 0.1], strict=True)]
    entry = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": noisy})
                         )["labels"]["x"]["fused.rmse_cm"]
    assert entry["verdict"] == "indistinguishable"
    assert entry["ci95"][0] < 0.0 < entry["ci95"][1]


def test_identical_runs_are_indistinguishable_with_a_zero_difference():
    run = rmse_run({"x": A_VALUES})
    result = compare_runs(run, run)
    for key in result["better_when"]:
        entry = result["labels"]["x"][key]
        assert entry["diff"] == 0.0 and entry["verdict"] == "indistinguishable", key


def test_all_pools_every_pair_and_counts_count_labels():
    a = rmse_run({"x": A_VALUES, "y": [10 * v for v in A_VALUES]})
    b = rmse_run({"x": B_LOWER, "y": [10 * v + d for v, d in
                                      zip(A_VALUES, [3, -3, 2, -2, 0], strict=True)]})
    result = compare_runs(a, b)
    pooled = result["all"]["fused.rmse_cm"]
    diffs = np.concatenate([np.subtract(B_LOWER, A_VALUES), [3, -3, 2, -2, 0]])
    assert pooled["n"] == 10 and pooled["diff"] == pytest.approx(diffs.mean())
    assert result["labels"]["y"]["fused.rmse_cm"]["verdict"] == "indistinguishable"
    assert result["counts"]["fused.rmse_cm"] == {"better": 1, "worse": 0,
                                                 "indistinguishable": 1}
    assert set(result["counts"]) == {m.key for m in DEFAULT_METRICS}


def test_a_seed_without_a_value_in_either_run_is_left_out_of_the_pairs():
    a = rmse_run({"x": A_VALUES})
    b = rmse_run({"x": [B_LOWER[0], NAN, *B_LOWER[2:]]})
    assert b["x"]["episodes"][1]["sources"]["fused"]["rmse_cm"] is None  # strict JSON: null
    entry = compare_runs(a, b)["labels"]["x"]["fused.rmse_cm"]
    kept = [0, 2, 3, 4]
    assert entry["n"] == 4
    assert entry["a_mean"] == pytest.approx(np.mean([A_VALUES[i] for i in kept]))
    assert entry["diff"] == pytest.approx(entry["b_mean"] - entry["a_mean"])


def test_default_metrics_and_their_direction():
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}))
    assert result["better_when"] == {
        "fused.rmse_cm": "lower", "fused.max_cm": "lower", "fused.ade_cm": "lower",
        "fused.fde_cm": "lower", "fused.valid_share": "higher", "car_rms_cm": "lower",
        "car_max_cm": "lower", "lane_departures": "lower"}
    entry = result["labels"]["x"]["lane_departures"]
    assert set(entry) == {"a_mean", "b_mean", "diff", "ci95", "verdict", "n"}


def test_metric_keys_parse_and_other_sources_add_their_metrics():
    assert parse_metric("hough:track.drift_cm").source == "hough:track"
    assert parse_metric("car_rms_cm").source is None
    assert parse_metric("fused.valid_share").lower_is_better is False
    with pytest.raises(ValueError, match="unknown metric 'fused.speed'"):
        parse_metric("fused.speed")
    keys = [m.key for m in metric_set(["car_rms_cm"], ["hough:track"])]
    assert keys == ["car_rms_cm", "hough:track.rmse_cm", "hough:track.max_cm",
                    "hough:track.ade_cm", "hough:track.fde_cm", "hough:track.valid_share"]
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}),
                          metric_set(sources=["hough:track"]))
    assert result["labels"]["x"]["hough:track.rmse_cm"]["verdict"] == "better"


def test_a_source_missing_in_a_run_is_named():
    a, b = rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER})
    with pytest.raises(IncomparableRuns, match="source 'lanenet:track' is not in A"):
        compare_runs(a, b, ["lanenet:track.rmse_cm"])
    del b["x"]["episodes"][2]["sources"]["hough:track"]
    with pytest.raises(IncomparableRuns, match=r"source 'hough:track' is not in B \(x seed 2 "
                                               r"has fused\)"):
        compare_runs(a, b, ["hough:track.rmse_cm"])


def test_other_labels_are_refused_naming_them():
    with pytest.raises(IncomparableRuns, match=r"different labels \(only in B: y\)"):
        compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER, "y": B_LOWER}))


def test_other_seeds_are_refused_naming_the_label():
    a = rmse_run({"x": A_VALUES})
    b = bench({"x": [episode(s + 10, v) for s, v in zip(SEEDS, B_LOWER, strict=True)]})
    with pytest.raises(IncomparableRuns, match=r"x: the runs have different seeds \(A: 0..4; "
                                               r"B: 10..14\)"):
        compare_runs(a, b)


@pytest.mark.parametrize("document", [
    json.loads(dumps(report_document(episode(0, 1.0), SCENARIO))),  # a `run --json` file
    {"clear_straight": {"schema_version": 1, "scenario": "clear_straight",
                        "sources": {"fused": {"rmse_cm": 1.0}}}},  # an old bench file
    [1, 2], {},
])
def test_a_document_that_is_no_bench_document_is_refused(document):
    with pytest.raises(IncomparableRuns) as err:
        compare_runs(rmse_run({"x": A_VALUES}), document)
    assert f"B: not a bench --json document (schema_version {SCHEMA_VERSION})" in str(err.value)
    assert "\n" not in str(err.value)


def test_another_scenario_file_is_a_note_not_a_refusal():
    a, b = rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER})
    b["x"]["scenario_sha256"] = "0" * 64
    result = compare_runs(a, b)
    assert result["labels"]["x"]["fused.rmse_cm"]["verdict"] == "better"
    assert any(n.startswith("scenario file differs: x") for n in result["notes"])
    assert not compare_runs(a, a)["notes"]


def test_an_episode_that_did_not_complete_is_noted():
    a = rmse_run({"x": A_VALUES})
    b = bench({"x": [episode(s, v, status="unstable" if s == 3 else "completed")
                     for s, v in zip(SEEDS, B_LOWER, strict=True)]})
    assert any("B: x seed 3 did not complete (unstable)" in n
               for n in compare_runs(a, b)["notes"])


def test_one_seed_gives_no_interval_and_says_so():
    a = bench({"x": [episode(0, 1.0)]})
    b = bench({"x": [episode(0, 0.5)]})
    result = compare_runs(a, b)
    entry = result["labels"]["x"]["fused.rmse_cm"]
    assert entry["diff"] == pytest.approx(-0.5) and entry["verdict"] == "indistinguishable"
    assert all(math.isnan(c) for c in entry["ci95"])
    assert any("one seed per label" in n for n in result["notes"])
    assert "-0.50 i" in compare_table(result)


def test_the_table_names_the_runs_what_differs_and_fits_120_columns():
    a = rmse_run({"clear_straight": A_VALUES, "a_rather_long_label@lanenet": A_VALUES})
    b = rmse_run({"clear_straight": B_LOWER, "a_rather_long_label@lanenet": A_VALUES},
                 controller="stanley")
    result = compare_runs(a, b, metric_set(sources=["hough:track"]),
                          a_name="before.json", b_name="after.json")
    text = compare_table(result)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH
    assert "A = before.json" in text and "B = after.json" in text
    assert "controller: (scenario file's) -> stanley" in text
    assert "better = B lower (higher for valid_share)" in text
    row = next(line for line in lines if line.startswith("clear_straight"))
    assert row.split()[1] == "-0.10" and row.split()[4] == "b"  # fused RMSE, verdict letter
    assert any(line.startswith("all (pooled)") for line in lines)
    assert "fused.rmse_cm 1b 0w 1i" in text
    assert "hough:track.rmse_cm" in text


def test_the_document_is_strict_json_with_a_schema_version():
    a = bench({"x": [episode(0, 1.0)]})
    doc = compare_document(compare_runs(a, a))
    assert doc["schema_version"] == SCHEMA_VERSION and "lanekeep_version" in doc
    back = json.loads(dumps(doc), parse_constant=lambda t: pytest.fail(f"not strict: {t}"))
    assert back["labels"]["x"]["fused.rmse_cm"]["ci95"] == [None, None]
