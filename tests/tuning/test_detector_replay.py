"""detector_replay's stretch of steps, per-step statistics and its bad-input lines (no
recording is rendered here: those need a drive)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lanekeep.tuning.detector_replay import GROSS_M, main, step_range, summarise


def test_a_stretch_of_steps_is_a_python_slice_of_the_recording():
    assert list(step_range("128:131", 250)) == [128, 129, 130]
    assert list(step_range(":2", 250)) == [0, 1]
    assert list(step_range("248:", 250)) == [248, 249]
    assert step_range(None, 5) == range(5)
    with pytest.raises(ValueError, match="holds none of the recording's 250 steps"):
        step_range("300:", 250)
    for bad in ("128", "a:b", "1:2:3"):
        with pytest.raises(ValueError, match="must be FIRST:END"):
            step_range(bad, 250)


def test_the_statistics_count_every_scored_step_a_missing_lane_included():
    errors = [0.0, 0.1, None, -2 * GROSS_M]
    s = summarise(errors, wall_s=0.4)
    assert s["valid_pct"] == pytest.approx(75.0)
    assert s["gross_pct"] == pytest.approx(25.0)  # one of four steps, not one of three lanes
    assert s["max_cm"] == pytest.approx(200 * GROSS_M)
    assert s["rmse_cm"] == pytest.approx(100 * np.sqrt((0.01 + 4 * GROSS_M ** 2) / 3))
    assert s["ms"] == pytest.approx(100.0)
    assert summarise([None, None], 0.0)["valid_pct"] == 0.0


def test_a_folder_that_is_no_recording_or_a_stretch_outside_it_is_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["score", str(tmp_path)])
    assert exit_info.value.code == 2
    assert "not a recording" in capsys.readouterr().err
    np.save(tmp_path / "truth.npy", np.zeros((10, 3)))
    (tmp_path / "meta.json").write_text(json.dumps({"scenario": "clear_straight"}))
    with pytest.raises(SystemExit) as exit_info:
        main(["score", str(tmp_path), "--steps", "20:30"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds none of the recording's 10 steps" in err
