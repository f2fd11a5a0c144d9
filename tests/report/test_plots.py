"""Episode plots: the truth at each estimate's own look-ahead, an error plot per source, titles
with scenario, seed and mode, and the files named on stderr."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import small_scenario_text

from lanekeep.cli.main import main


@pytest.mark.slow
def test_run_writes_offsets_and_errors_per_source_and_names_the_files(tmp_path, capsys):
    scenario = tmp_path / "small.toml"
    scenario.write_text(small_scenario_text("clear_curve", 3.0, keep_criteria=True),
                        encoding="utf-8")
    out = tmp_path / "plots"
    assert main(["run", str(scenario), "--seconds", "1", "--plots", str(out), "--seed", "3"]) \
        in (0, 1)
    err = capsys.readouterr().err
    for name in ("offsets.png", "errors.png", "probabilities.png", "top_view.png"):
        assert (out / name).stat().st_size > 0
        assert f"wrote {out / name}" in err


def _fake_step(i: int, road):
    from types import SimpleNamespace

    from lanekeep.detectors.base import LaneEstimate
    from lanekeep.scoring.metrics import ADE_POINTS_M
    from lanekeep.scoring.step_truth import step_truth

    est = {"hough": LaneEstimate(True, 0.1 + 0.01 * i, 6.0, np.array([1.8, 0, 0]),
                                 np.array([-1.8, 0, 0]), 0.9),
           "sliding_window": LaneEstimate.invalid("no paint", 8.0)}
    pose = (10.0 + i, 0.0, 0.0)
    truth = step_truth(road, 0, pose, pose, [6.0, 8.0, -5.0], np.asarray(ADE_POINTS_M))
    return SimpleNamespace(time_s=0.1 * (i + 1), truth=truth, output_x_m=6.0, reference_x_m=-5.0,
                           estimates=est,
                           track_offsets_m={"hough": 0.08, "sliding_window": None},
                           output_offset_m=0.09, reference_m=0.0, probabilities=[0.7, 0.3],
                           mmae_residuals_m=np.array([-0.02, np.nan]),
                           pose=pose, sensed_pose=pose)


def test_errors_are_against_the_truth_at_each_estimates_own_look_ahead(tmp_path):
    import matplotlib.image as mpimg

    import lanekeep  # noqa: F401 - EGL before mujoco
    from lanekeep.report.plots import EpisodeTrace, write_plots
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_offsets
    from lanekeep.world.build import build

    scenario = load_scenario("clear_straight")
    road = build(scenario).road
    trace = EpisodeTrace(["hough", "sliding_window"])
    for i in range(5):
        trace.add(_fake_step(i, road))
    errors = trace.errors_cm()
    assert list(errors) == ["hough", "hough:track", "sliding_window", "sliding_window:track",
                            "fused", "reference"]
    truth_6 = lane_offsets(road, 10.0, 0.0, 0.0, 0, [6.0])[0]
    truth_ref = lane_offsets(road, 10.0, 0.0, 0.0, 0, [-5.0])[0]
    assert errors["hough"][0] == pytest.approx((0.1 - truth_6) * 100)
    assert errors["reference"][0] == pytest.approx((0.0 - truth_ref) * 100)
    assert errors["fused"][0] == pytest.approx((0.09 - truth_6) * 100)  # at the output's x
    assert np.isnan(errors["sliding_window"]).all()  # never valid: no error to draw
    residuals = np.asarray(trace.residuals_m)  # the MMAE's, drawn under its probabilities
    assert residuals.shape == (5, 2) and np.allclose(residuals[:, 0], -0.02)
    assert np.isnan(residuals[:, 1]).all()
    files = write_plots(trace, road, tmp_path, "clear_straight (seed 0, mode default)")
    assert [f.name for f in files] == ["offsets.png", "errors.png", "probabilities.png",
                                       "top_view.png"]
    assert mpimg.imread(files[1]).shape[0] > mpimg.imread(files[2]).shape[0]  # 6 panels


def test_titles_name_scenario_seed_and_mode():
    from lanekeep.report.plots import plot_title
    from lanekeep.scenario.schema import load_scenario

    title = plot_title(load_scenario("sharp_turn"))
    assert title.startswith("sharp_turn (seed ") and "mode default" in title
