"""The tuning scenarios (lanekeep/tuning/scenario_files/), on which the closed loop's tracker
noise is measured, and the tuning tools (lanekeep/tuning/) run by their scripts in tools/.

They must load and build, and stay apart from the shipped scenarios that `lanekeep bench`
scores; lanekeep.tuning.detector_noise refuses a shipped one unless told --allow-scored.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.tuning import replay, trace
from lanekeep.tuning.estimation import Setting, typed_value
from lanekeep.tuning.scenarios import (
    TuningInputError,
    own_seed,
    select_scenarios,
    tuning_dir,
    tuning_scenarios,
)
from lanekeep.world.build import build

TOOLS = Path(__file__).resolve().parents[2] / "tools"
TUNING_DIR = tuning_dir()
TUNING = sorted(TUNING_DIR.glob("*.toml"))


def _tool(name: str, *args: str) -> subprocess.CompletedProcess:
    """tools/<name>.py run with `args`, as from a shell (its exit status and output)."""
    return subprocess.run([sys.executable, str(TOOLS / f"{name}.py"), *args],
                          capture_output=True, text=True, timeout=300)


def test_there_are_tuning_scenarios():
    assert len(TUNING) >= 4


@pytest.mark.parametrize("path", TUNING, ids=lambda p: p.stem)
def test_tuning_scenario_loads_and_builds(path):
    scenario = load_scenario(path)
    assert scenario.name == path.stem
    assert "not scored by the bench" in scenario.description
    build(scenario)  # shadow casters against the sun, segments, markings: checked at build


def test_tuning_scenarios_are_not_shipped():
    shipped = set(shipped_scenarios())
    names = {load_scenario(path).name for path in TUNING}
    assert not names & shipped
    shipped_seeds = {load_scenario(name).seed for name in shipped}
    assert not {load_scenario(path).seed for path in TUNING} & shipped_seeds


def test_noise_tool_defaults_to_the_tuning_scenarios():
    assert tuning_scenarios(TUNING_DIR) == tuning_scenarios() == TUNING
    assert sorted(Path(a) for a in select_scenarios([], TUNING_DIR)) == TUNING  # not scored


@pytest.mark.parametrize("arg", ["clear_straight", "case2_sharp_turn"])
def test_noise_tool_refuses_a_shipped_scenario(arg):
    refused = _tool("measure_detector_noise", str(TUNING[0]), arg)
    assert refused.returncode == 2
    assert "--allow-scored" in refused.stderr
    with pytest.raises(TuningInputError, match="--allow-scored"):
        select_scenarios([str(TUNING[0]), arg], TUNING_DIR)
    assert select_scenarios([arg], TUNING_DIR, allow_scored=True) == [arg]
    allowed = _tool("measure_detector_noise", arg, "--allow-scored", "--list")
    assert allowed.returncode == 0 and allowed.stdout.split() == [arg]


def test_noise_tool_refuses_a_shipped_scenario_file():
    path = Path(load_scenario("fog").source)
    assert _tool("measure_detector_noise", str(path)).returncode == 2


def test_compare_tool_defaults_to_the_tuning_scenarios_and_refuses_scored_ones():
    assert sorted(Path(a) for a in select_scenarios([], TUNING_DIR)) == TUNING
    setting = Setting.parse("output=select,fused")
    assert (setting.key, list(setting.values)) == ("output", ["select", "fused"])
    assert _tool("compare_estimation", "output=fused", "clear_curve").returncode == 2
    assert _tool("compare_estimation", "no_such_key=1").returncode == 2
    with pytest.raises(TuningInputError):
        Setting.parse("no_such_key=1")
    assert [typed_value(bool, v) for v in ("true", "false")] == [True, False]
    for bad in ("offset_lookahead_m=far", "reference_std_m=0.05,"):
        assert _tool("compare_estimation", bad).returncode == 2
        with pytest.raises(TuningInputError):
            Setting.parse(bad)


def test_trace_tool_tells_a_model_that_errs_with_the_reference_from_one_that_errs_against_it():
    """The residual summary: a model whose carried offset errs with the reference keeps a
    residual of its bias alone (correlation +1); one that errs against it pays for both
    (correlation -1); steps the MMAE did not compare (NaN) are left out."""
    rng = np.random.default_rng(0)
    reference_error = rng.normal(0.0, 0.01, 200)
    bias = 0.01
    with_it = reference_error + bias  # the carried offset's error
    against_it = -reference_error
    columns = {"reference": reference_error,
               "with:residual": reference_error - with_it,
               "against:residual": reference_error - against_it}
    columns["against:residual"][:10] = np.nan
    summary = trace.residual_summary(["with", "against"], columns)
    assert summary["with"]["mean_m"] == pytest.approx(-bias)
    assert summary["with"]["rms_m"] == pytest.approx(bias)
    assert summary["with"]["correlation"] == pytest.approx(1.0)
    assert summary["against"]["correlation"] == pytest.approx(-1.0)
    assert summary["against"]["rms_m"] == pytest.approx(
        2.0 * np.sqrt(np.mean(reference_error[10:] ** 2)))


def test_trace_tool_shows_when_the_output_accrues_its_excess_over_a_track():
    """Windows of the output's squared error minus a track's: a loss made in the first second
    lands in the first window; steps where either is missing count for neither."""
    time = np.arange(1, 41) * 0.1  # 4 s of 0.1 s steps
    track = np.full(40, 0.005)
    fused = track.copy()
    fused[:10] = 0.01  # the first second: 1 cm against 0.5 cm
    fused[25] = np.nan
    columns = {"time": time, "fused": fused, "a:track": track,
               "a:p": np.full(40, 0.9), "b:p": np.full(40, 0.1)}
    rows = trace.excess_by_window(["a", "b"], columns, "a:track", 2.0)
    assert [r[0] for r in rows] == pytest.approx([0.1, 2.1])
    assert rows[0][1] == pytest.approx(10 * (0.01**2 - 0.005**2))
    assert rows[1][1] == pytest.approx(0.0)
    np.testing.assert_allclose(rows[0][2], [0.9, 0.1])
    assert _tool("trace_estimation", "clear_curve", "--window", "0").returncode == 2


def _synthetic_recording(steps: int = 60) -> dict:
    """A straight drive at 15 m/s on the lane's centre: hough reads it exactly, sliding_window
    5 cm to one side, the rear reference exactly."""
    from lanekeep.detectors.base import LaneEstimate
    from lanekeep.estimators.lane_estimator import EgoMotion, EstimatorSettings

    def lane(c0: float, x_m: float) -> LaneEstimate:
        return LaneEstimate(valid=True, offset_m=-c0, x_m=x_m, left=np.array([c0 + 1.85, 0, 0]),
                            right=np.array([c0 - 1.85, 0, 0]))

    rows = [{"detections": {"hough": lane(0.0, 4.0), "sliding_window": lane(0.05, 4.0)},
             "reference": lane(0.0, -4.0),
             "ego": EgoMotion(0.1, 15.0, 0.0, 0.0, (1.5 * k, 0.0, 0.0), 1.5 * (k + 1)),
             "truth_m": 0.0} for k in range(steps)]
    settings = EstimatorSettings(lane_width_prior_m=3.7, output="precision")
    return {"scenario": "synthetic", "names": ["hough", "sliding_window"],
            "settings": settings, "reference_x_m": -4.0, "steps": rows}


def test_replay_tool_scores_estimator_settings_on_a_recorded_drive(tmp_path):
    """Open-loop replay: the biased model's weight reaches the output until the reference
    has taken it away, faster with a smaller eq. 8 noise; the exact model's track is the
    best. A bad key or value, a directory without recordings or with a file that is not one:
    one line, exit 2."""
    import pickle

    rows = replay.compare([_synthetic_recording()], "reference_std_m", [0.05, 0.01])
    (_, _, slow, best, model), (_, _, fast, best_again, _) = rows
    assert model == "hough" and best == pytest.approx(best_again) and best < 0.05
    assert best < fast < slow < 5.0
    with (tmp_path / "synthetic.pkl").open("wb") as f:
        pickle.dump(_synthetic_recording(10), f)
    ok = _tool("replay_estimation", "compare", str(tmp_path), "prefer_accepted=true,false")
    assert ok.returncode == 0, ok.stderr
    junk = tmp_path / "junk"
    junk.mkdir()
    (junk / "a.pkl").write_bytes(b"not a pickle")
    for bad in (["compare", str(tmp_path), "no_such_key=1"],
                ["compare", str(tmp_path), "reference_std_m=small"],
                ["compare", str(tmp_path), "residual_mode=distance-aligned"],
                ["compare", str(tmp_path), "lane_width_range_m=3"],
                ["compare", str(tmp_path / "none"), "reference_std_m=0.05"],
                ["compare", str(junk), "reference_std_m=0.05"]):
        assert _tool("replay_estimation", *bad).returncode == 2, bad


def test_replay_tool_records_a_shipped_scenario_only_at_a_seed_the_bench_does_not_score(
        tmp_path):
    """The bench scores each shipped scenario at its file's seed: recording it there is
    refused (exit 2, before anything drives); another seed is unscored data, named apart."""
    own = own_seed("fog")
    assert isinstance(own, int)
    scored = _tool("replay_estimation", "record", str(tmp_path), "fog", "--seed", str(own))
    assert scored.returncode == 2
    negative = _tool("replay_estimation", "record", str(tmp_path), "fog", "--seed", "-1")
    assert negative.returncode == 2
    assert not list(tmp_path.iterdir())
    assert replay.path_stem("fog", own + 1) == f"fog_seed{own + 1}"
    assert replay.path_stem("fog", None) == "fog"
