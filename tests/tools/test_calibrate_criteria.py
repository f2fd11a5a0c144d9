"""Criteria calibration (lanekeep/tuning/criteria_calibration.py, tools/calibrate_criteria.py)
and the sabotage plug-in that the calibrated criteria must catch (examples/sabotage.py).

Bench documents are built from made-up episode reports through the bench's own summary
(lanekeep/report/seed_summary.py): no episode runs here.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import t

from lanekeep.detectors.base import LaneEstimate
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import EpisodeReport, SourceReport
from lanekeep.tuning.criteria_calibration import (
    GEOMETRY,
    Calibration,
    calibrate,
    check_full_length,
    criteria_block,
    fused_rmse_limit_m,
    geometry_note,
    rewrite_criteria,
)
from lanekeep.tuning.scenarios import SCORED_SEEDS, TUNING_SEEDS_START

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "calibrate_criteria.py"
SCENARIO = "case1_building_shadows"
VALUES = [1.0, 1.1, 0.9, 1.0, 1.05]
COMMAND = ("lanekeep bench --seed 1000 --seeds 5 --json tuning.json && "
           "python tools/calibrate_criteria.py tuning.json --write")


def _bound_cm(values: list[float]) -> float:
    x = np.asarray(values)
    k = len(x)
    return float(x.mean() + t.ppf(0.999, k - 1) * x.std(ddof=1) * math.sqrt(1 + 1 / k))


def _report(name: str, seed: int, rmse_cm: float, status: str = "completed",
            car_max_cm: float = 12.0, departures: int = 0) -> EpisodeReport:
    scenario = load_scenario(name)
    steps = round(scenario.duration_s / scenario.control_period_s)
    sources = {"fused": SourceReport(rmse_cm, 3 * rmse_cm, 1.0, 2.0, 1.0, 0.1),
               "hough:track": SourceReport(rmse_cm + 0.5, 4.0, 1.0, 2.0, 1.0, 0.1),
               "reference": SourceReport(2.0, 5.0, math.nan, math.nan, 0.9)}
    return EpisodeReport(scenario=name, seed=seed, duration_s=steps * scenario.control_period_s,
                         steps=steps, sources=sources, car_rms_cm=5.0, car_max_cm=car_max_cm,
                         lane_departures=departures, mmae_switches=1, no_estimate_s=0.0,
                         reference_repairs=0, completed=status == "completed",
                         status=status, stop_reason="" if status == "completed" else status)


def _bench(values: list[float] = VALUES, first: int = TUNING_SEEDS_START,
           name: str = SCENARIO, **episode) -> dict:
    """A `bench --seeds N --json` file's content, one scenario, the fused RMSE `values`."""
    reports = [_report(name, first + i, v, **episode) for i, v in enumerate(values)]
    return {name: summarise(name, reports, load_scenario(name))}


def _tool(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)


# -- the rule -------------------------------------------------------------------------------

def test_the_seed_ranges_meet():
    assert SCORED_SEEDS.stop == TUNING_SEEDS_START == 1000 and SCORED_SEEDS.start == 0


def test_the_limit_is_the_prediction_bound_rounded_up_to_a_tenth_of_a_cm():
    bound = _bound_cm(VALUES)  # 1.01 + t(0.999, 4) 0.0742 sqrt(1.2) = 1.6
    assert 1.5 < bound < 1.7
    limit = fused_rmse_limit_m(VALUES)
    assert limit == pytest.approx(math.ceil(bound * 10) / 1000)
    assert 0 <= 100 * limit - bound < 0.1


def test_the_limit_rounds_up_exactly_and_widens_with_fewer_seeds():
    assert fused_rmse_limit_m([1.2, 1.2, 1.2]) == 0.012  # a bound on a step stays on it
    same_spread = [2.0, 2.2, 1.8]
    many = same_spread * 4  # about the same sd, K = 12: t(0.999, 11) = 4.0, not 22.3
    assert fused_rmse_limit_m(same_spread) > fused_rmse_limit_m(many) > 0.02
    assert 100 * fused_rmse_limit_m(many) == pytest.approx(
        math.ceil(_bound_cm(many) * 10) / 10)


@pytest.mark.parametrize("values", [[], [1.0], [1.0, 1.1], [1.0, math.nan, 1.2]])
def test_the_limit_needs_three_finite_values(values):
    with pytest.raises(ValueError):
        fused_rmse_limit_m(values)


# -- calibrating a bench document -----------------------------------------------------------

def test_calibrate_reads_each_seed_of_the_bench_document():
    cal = calibrate(_bench(car_max_cm=14.5))[SCENARIO]
    assert cal.scenario == SCENARIO and cal.seeds == (1000, 1001, 1002, 1003, 1004)
    assert cal.mean_cm == pytest.approx(np.mean(VALUES))
    assert cal.sd_cm == pytest.approx(np.std(VALUES, ddof=1))
    assert cal.limit_m == fused_rmse_limit_m(VALUES)
    assert cal.car_max_cm_max == 14.5 and cal.departures_max == 0
    check_full_length(cal, load_scenario(SCENARIO))  # full episodes


def test_calibrate_leaves_the_model_only_loops_out():
    doc = _bench()
    doc[f"{SCENARIO}@hough"] = doc[SCENARIO] | {"label": f"{SCENARIO}@hough"}
    assert list(calibrate(doc)) == [SCENARIO]


@pytest.mark.parametrize(("doc", "message"), [
    (_bench(first=998), r"seeds \[998, 999\] are scored by the bench"),
    (_bench(first=0), "scored by the bench"),
    (_bench(VALUES[:2]), "2 seeds, at least 3"),
    (_bench(status="off_road"), "seed 1000 did not complete"),
    (_bench([1.0, math.nan, 1.1]), "seed 1001 has no fused RMSE"),
    ({SCENARIO: {"scenario": SCENARIO, "seed": 1000}}, "no 'episodes'"),
    ([], "not a `bench --json` file"),
])
def test_calibrate_refuses_what_is_no_calibration(doc, message):
    with pytest.raises(ValueError, match=message) as err:
        calibrate(doc)
    assert "\n" not in str(err.value)


def test_calibrate_refuses_a_loop_changed_on_the_command_line():
    doc = _bench()
    doc[SCENARIO]["overrides"] = {"front_detectors": ["hough"], "reference_detector": None}
    with pytest.raises(ValueError, match="calibrate the scenario as shipped"):
        calibrate(doc)


def test_a_short_bench_is_no_calibration():
    cal = calibrate(_bench())[SCENARIO]
    short = Calibration(**{**cal.__dict__, "duration_s_min": 3.0})
    with pytest.raises(ValueError, match="ran 3 s of the scenario's"):
        check_full_length(short, load_scenario(SCENARIO))


# -- writing it into a scenario file --------------------------------------------------------

def test_the_block_round_trips_through_a_copy_of_a_shipped_file(tmp_path):
    shipped = Path(load_scenario(SCENARIO).source)
    path = tmp_path / f"{SCENARIO}.toml"
    shutil.copy(shipped, path)
    before = load_scenario(path)
    cal = calibrate(_bench())[SCENARIO]
    block = criteria_block(cal, COMMAND, "2026-12-01", geometry_note(path.read_text()))
    assert block.startswith("# Pass/fail") and block.endswith("\n")
    assert COMMAND in block and "2026-12-01" in block and "K = 5 tuning seeds (1000-1004" in block
    assert "1.01 cm mean" in block and "0.07 cm sd" in block and "car max up to 12.0 cm" in block
    assert max(len(line) for line in block.splitlines() if line != f"#   {COMMAND}") <= 100
    after = rewrite_criteria(path, block)
    assert after.criteria.max_fused_rmse_m == cal.limit_m == pytest.approx(0.016)
    assert after.criteria.max_lane_departures == 0
    assert after.criteria.max_car_lateral_error_m == 0.5
    # everything above the block is the file's own; the block replaced the old one whole
    assert after == before.__class__(**{**before.__dict__, "criteria": after.criteria})
    text = path.read_text()
    assert text.count("# Pass/fail") == 1 and text.count("[criteria]") == 1
    assert text.startswith(shipped.read_text().split("# Pass/fail")[0])
    assert rewrite_criteria(path, block) == after  # again: the same file
    assert path.read_text() == text


def test_the_car_error_explanation_of_the_file_is_kept():
    wide = Path(load_scenario("highway_multilane").source).read_text()
    assert geometry_note(wide) == ("half the 1.07 m between a wheel and the line: 3.75 m lane, "
                                   "1.62 m track")
    assert geometry_note("[criteria]\n") == GEOMETRY
    cal = calibrate(_bench())[SCENARIO]
    block = criteria_block(cal, COMMAND, "2026-12-01", geometry_note(wide))
    assert geometry_note(block) == geometry_note(wide)  # a rewritten file keeps it too


def test_rewrite_refuses_a_file_without_the_block(tmp_path):
    path = tmp_path / "bare.toml"
    text = Path(load_scenario(SCENARIO).source).read_text().split("# Pass/fail")[0]
    path.write_text(text)
    with pytest.raises(ValueError, match="no '# Pass/fail' line"):
        rewrite_criteria(path, "# Pass/fail\n[criteria]\nmax_fused_rmse_m = 0.02\n")
    assert path.read_text() == text


def test_rewrite_leaves_the_file_alone_when_the_block_does_not_load(tmp_path):
    path = tmp_path / f"{SCENARIO}.toml"
    shutil.copy(load_scenario(SCENARIO).source, path)
    text = path.read_text()
    with pytest.raises(ValueError):
        rewrite_criteria(path, "# Pass/fail\n[criteria]\nmax_fused_rmse_m = -1\n")
    assert path.read_text() == text


# -- the tool --------------------------------------------------------------------------------

def test_the_tool_prints_the_table_and_writes_nothing_without_write(tmp_path):
    path = tmp_path / "tuning.json"
    path.write_text(json.dumps(_bench()))
    shipped = Path(load_scenario(SCENARIO).source)
    text = shipped.read_text()
    done = _tool(str(path))
    assert done.returncode == 0, done.stderr
    header, row = done.stdout.splitlines()
    assert header.split() == ["scenario", "K", "mean", "cm", "sd", "cm", "old", "cm", "new", "cm"]
    old = 100 * load_scenario(SCENARIO).criteria.max_fused_rmse_m
    assert row.split() == [SCENARIO, "5", "1.01", "0.07", f"{old:.1f}", "1.6"]
    assert shipped.read_text() == text


@pytest.mark.parametrize(("content", "message"), [
    ("{not json", "not JSON"),
    (json.dumps(_bench(first=0)), "scored by the bench"),
    (json.dumps(_bench(VALUES[:2])), "at least 3"),
    (json.dumps(_bench(status="unstable")), "did not complete"),
])
def test_the_tool_says_what_is_wrong_in_one_line_and_exits_2(tmp_path, content, message):
    path = tmp_path / "bench.json"
    path.write_text(content)
    done = _tool(str(path), "--write")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("calibrate_criteria: ") and message in done.stderr
    assert done.stderr.count("\n") == 1


def test_the_tool_exits_2_on_a_missing_file_and_a_bad_date(tmp_path):
    done = _tool(str(tmp_path / "none.json"))
    assert done.returncode == 2 and "none.json" in done.stderr
    path = tmp_path / "tuning.json"
    path.write_text(json.dumps(_bench()))
    done = _tool(str(path), "--date", "yesterday")
    assert done.returncode == 2 and "YYYY-MM-DD" in done.stderr


# -- the sabotage plug-in --------------------------------------------------------------------

def test_the_sabotage_moves_the_lane_and_the_offset_together(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))  # as `python -m lanekeep.cli` from the root has it
    from examples.sabotage import BIAS_M, biased

    left, right = np.array([1.85, 0.01, 0.001]), np.array([-1.85, 0.01, 0.001])
    x = 8.0
    centre = (left + right) / 2
    honest = LaneEstimate(valid=True, offset_m=float(LanePoly.of(centre).offset_m(x)), x_m=x,
                          left=left, right=right, confidence=0.8)
    moved = biased(honest)
    assert BIAS_M == 0.05
    assert moved.left[0] == pytest.approx(1.90) and moved.right[0] == pytest.approx(-1.80)
    assert np.allclose(moved.left[1:], left[1:]) and np.allclose(moved.right[1:], right[1:])
    # the offset still says where the centre line is (at y = -offset_m), now 5 cm left
    assert -moved.offset_m == pytest.approx(float(LanePoly.of(moved.center).y(x)))
    assert moved.offset_m == pytest.approx(honest.offset_m - 0.05)
    assert honest.left[0] == 1.85  # the detector's own estimate is not changed
    assert moved.confidence == 0.8 and moved.x_m == x
    one_side = biased(LaneEstimate(valid=True, offset_m=0.1, x_m=x, left=left), 0.02)
    assert one_side.right is None and one_side.left[0] == pytest.approx(1.87)
    nothing = LaneEstimate.invalid("no paint")
    assert biased(nothing) is nothing


def test_the_sabotage_classes_resolve_by_import_path_from_the_repository_root(monkeypatch):
    from lanekeep.detectors.registry import takes_weights

    code = ("from lanekeep.core.plugins import DETECTORS, load_import_path\n"
            "for c in ('BiasedHough', 'BiasedSlidingWindow', 'BiasedLaneNet'):\n"
            "    print(load_import_path('examples.sabotage:' + c, DETECTORS).inner_name)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["hough", "sliding_window", "lanenet"]
    monkeypatch.syspath_prepend(str(ROOT))
    assert takes_weights("examples.sabotage:BiasedLaneNet")  # --weights reaches LaneNet
    assert not takes_weights("examples.sabotage:BiasedHough")
