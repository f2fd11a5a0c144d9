"""The JSON reports are strict JSON and say where they came from.

Strict: a parser that refuses NaN / Infinity (as jq and a browser's JSON.parse do) reads them;
a number an episode could not measure is null. Each report carries the schema version, the
lanekeep version, the SHA-256 of the scenario file and the seed.
"""

import dataclasses
import hashlib
import json
import math
from pathlib import Path

import pytest

from lanekeep.cli.main import main
from lanekeep.report.json_io import (
    SCHEMA_VERSION,
    lanekeep_version,
    report_document,
    report_from_dict,
    scenario_sha256,
    strict,
    write_json,
)
from lanekeep.scenario.schema import load_scenario, parse_scenario
from lanekeep.scoring.metrics import CommonSteps, EpisodeReport, SourceReport

NAN = math.nan


def _refuse(token: str):
    raise ValueError(f"not strict JSON: {token}")


def strict_load(path: Path):
    """json.loads that fails on NaN, Infinity and -Infinity, like jq or JSON.parse."""
    return json.loads(Path(path).read_text(), parse_constant=_refuse)


def _sha256(name: str) -> str:
    return hashlib.sha256(Path(load_scenario(name).source).read_bytes()).hexdigest()


def _assert_metadata(doc: dict, scenario: str, seed: int) -> None:
    assert doc["schema_version"] == SCHEMA_VERSION == 2
    assert doc["lanekeep_version"] == lanekeep_version() != ""
    assert doc["scenario_sha256"] == _sha256(scenario)
    assert doc["seed"] == seed
    assert doc["scenario"] == scenario


def _nan_report() -> EpisodeReport:
    sources = {"hough": SourceReport(1.5, 3.0, NAN, NAN, 0.5),
               "reference": SourceReport(NAN, NAN, NAN, NAN, 0.0)}
    return EpisodeReport(scenario="clear_straight", seed=4, duration_s=0.0, steps=0,
                         sources=sources, car_rms_cm=NAN, car_max_cm=math.inf,
                         lane_departures=0, mmae_switches=0, no_estimate_s=0.0,
                         reference_repairs=0)


def test_the_strict_parser_refuses_what_pythons_json_writes_by_default(tmp_path):
    path = tmp_path / "loose.json"
    path.write_text(json.dumps({"ade_cm": NAN}))
    with pytest.raises(ValueError, match="NaN"):
        strict_load(path)


def test_run_json_is_strict_and_carries_version_hash_and_seed(tmp_path, capsys):
    out = tmp_path / "run.json"
    assert main(["run", "clear_straight", "--seconds", "0.3", "--seed", "7",
                 "--json", str(out)]) == 0
    doc = strict_load(out)
    _assert_metadata(doc, "clear_straight", seed=7)  # the --seed the episode ran with
    assert doc["steps"] == 3
    assert set(doc["sources"]) >= {"fused", "reference"}
    back = report_from_dict(doc)  # the metadata does not stop a round trip
    assert back.seed == 7 and back.steps == 3 and set(back.sources) == set(doc["sources"])
    assert [p.name for p in tmp_path.iterdir()] == ["run.json"]  # no temporary file left


def test_a_report_with_nan_fields_writes_null_and_reads_back_nan(tmp_path):
    report = _nan_report()
    scenario = load_scenario("clear_straight")
    path = write_json(tmp_path / "nan.json", report_document(report, scenario))
    doc = strict_load(path)
    assert doc["sources"]["reference"] == {"rmse_cm": None, "max_cm": None, "ade_cm": None,
                                           "fde_cm": None, "valid_share": 0.0,
                                           "drift_cm": None, "reference_error_corr": None}
    assert doc["sources"]["hough"]["ade_cm"] is None and doc["sources"]["hough"]["rmse_cm"] == 1.5
    assert doc["car_rms_cm"] is None and doc["car_max_cm"] is None  # NaN and infinity alike
    assert doc["seed"] == 4 and doc["scenario_sha256"] == _sha256("clear_straight")
    back = report_from_dict(doc)
    assert math.isnan(back.car_rms_cm) and math.isnan(back.sources["reference"].ade_cm)
    assert back.sources["hough"].rmse_cm == 1.5
    assert back.ade_range_m == report.ade_range_m and back.sources.keys() == report.sources.keys()


def test_bench_json_is_strict_with_metadata_in_each_report(tmp_path, capsys):
    out = tmp_path / "bench.json"
    assert main(["bench", "clear_straight", "--seconds", "0.3", "--workers", "1",
                 "--json", str(out)]) == 0
    data = strict_load(out)
    assert list(data) == ["clear_straight"]  # keyed by scenario label, as before
    _assert_metadata(data["clear_straight"], "clear_straight", seed=0)
    assert data["clear_straight"]["seeds"] == [0]
    (episode,) = data["clear_straight"]["episodes"]  # each seed's own report
    _assert_metadata(episode, "clear_straight", seed=0)
    assert report_from_dict(episode).steps == 3


def test_perf_json_is_strict_with_metadata(tmp_path, capsys):
    out = tmp_path / "perf.json"
    assert main(["perf", "--scenario", "clear_straight", "--seconds", "0.1", "--repeats", "1",
                 "--bench-episodes", "0", "--json", str(out)]) == 0
    doc = strict_load(out)
    assert doc["schema_version"] == SCHEMA_VERSION
    assert doc["lanekeep_version"] == lanekeep_version()
    assert doc["scenario_sha256"] == _sha256("clear_straight")
    assert doc["seed"] == 0 and doc["scenario"] == "clear_straight" and doc["bench"] is None


def test_an_in_memory_scenario_is_hashed_by_its_canonical_form():
    text = Path(load_scenario("clear_straight").source).read_text()
    a, b = parse_scenario(text), parse_scenario(text)  # source "<string>": no file
    assert scenario_sha256(a) == scenario_sha256(b)
    other = parse_scenario(text.replace("seed = 0", "seed = 1"))
    assert scenario_sha256(other) != scenario_sha256(a)


def test_strict_replaces_every_non_finite_number_recursively():
    import numpy as np

    value = {"a": [1.0, NAN, {"b": (math.inf, -math.inf)}], "c": np.float64("nan"),
             "d": np.array([1.0, np.nan]), "e": "NaN", "f": None, "g": 3}
    assert strict(value) == {"a": [1.0, None, {"b": [None, None]}], "c": None,
                             "d": [1.0, None], "e": "NaN", "f": None, "g": 3}


def test_write_json_is_atomic(tmp_path):
    path = tmp_path / "report.json"
    write_json(path, {"v": 1})
    with pytest.raises(TypeError):
        write_json(path, {"v": object()})  # cannot be serialised: the old file stays whole
    assert strict_load(path) == {"v": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]
    write_json(tmp_path / "new" / "deeper.json", [NAN])  # folders are made
    assert strict_load(tmp_path / "new" / "deeper.json") == [None]


def test_fused_vs_track_survives_the_json_round_trip(tmp_path):
    """The common-step comparison is written (NaN as null, a track never beside the output)
    and read back as CommonSteps (report_from_dict: what a bench worker's report becomes)."""
    common = {"hough:track": CommonSteps(1.25, 0.75, 8, 0.8),
              "lanenet:track": CommonSteps(NAN, NAN, 0, 0.0)}
    report = dataclasses.replace(_nan_report(), fused_vs_track=common)
    path = write_json(tmp_path / "common.json",
                      report_document(report, load_scenario("clear_straight")))
    doc = strict_load(path)
    assert doc["fused_vs_track"] == {
        "hough:track": {"rmse_a_cm": 1.25, "rmse_b_cm": 0.75, "steps": 8, "share": 0.8},
        "lanenet:track": {"rmse_a_cm": None, "rmse_b_cm": None, "steps": 0,
                          "share": 0.0}}
    back = report_from_dict(doc)
    assert back.fused_vs_track["hough:track"] == common["hough:track"]
    assert math.isnan(back.fused_vs_track["lanenet:track"].rmse_a_cm)
    assert back.fused_vs_track["lanenet:track"].steps == 0
    assert report_from_dict(report.to_dict()).fused_vs_track["hough:track"] == common[
        "hough:track"]  # the bench worker's path: to_dict() in the worker, back in the parent
    assert report_from_dict({k: v for k, v in doc.items() if k != "fused_vs_track"}
                            ).fused_vs_track == {}  # a document from before the key
