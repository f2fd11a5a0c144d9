"""lanekeep/tuning/classical_errors.py's calibration table: per confidence band of the valid
frames, the share whose ego offset is within 10 cm (what a detector's confidence says)."""

import math

from lanekeep.tuning.classical_errors import calibration, summary


def _record(valid: bool, confidence: float, error_m: float) -> dict:
    return {"valid": valid, "reason": "" if valid else "no lines", "confidence": confidence,
            "error_m": error_m}


def test_calibration_counts_each_band_and_the_share_within_10_cm():
    records = [_record(True, 0.9, 0.02), _record(True, 0.95, 0.30), _record(True, 1.0, 0.05),
               _record(True, 0.1, 0.50), _record(False, 0.9, math.nan),
               _record(True, 0.5, math.nan)]  # unscored (no labelled ego pair): left out
    bands = calibration(records)
    assert [b["frames"] for b in bands] == [1, 0, 0, 0, 3]
    assert bands[0]["share_ok"] == 0.0 and math.isnan(bands[1]["share_ok"])
    assert bands[-1]["to"] == 1.0 and bands[-1]["share_ok"] == 2 / 3  # confidence 1 included
    text = summary(records)
    assert "0.8-1.0: 3 frames, 67% within 10 cm" in text and "0.2-0.4: 0 frames, -" in text


def test_a_bad_detectors_config_is_one_line_and_exit_2(tmp_path, capsys):
    from lanekeep.tuning.classical_errors import main

    bad = tmp_path / "bad.toml"
    bad.write_text("[preprocess]\njoin_min_dots = 1\n")
    assert main(["--detectors-config", str(bad), "--cache", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "join_min_dots" in err and "Traceback" not in err


def test_quick_reads_the_one_world_set_of_the_split_asked(monkeypatch, tmp_path, capsys):
    """`--quick` is `lanekeep eval --quick`'s set (one world, one sequence) of the split asked."""
    from lanekeep.tuning import classical_errors

    asked = []

    def fake_frame_errors(detector, condition, recipe, cache, config=None):
        asked.append(recipe)
        return [], {}

    monkeypatch.setattr(classical_errors, "frame_errors", fake_frame_errors)
    for argv in (["--quick"], ["--quick", "--split", "test"], []):
        assert classical_errors.main([*argv, "--worst", "0", "--cache", str(tmp_path)]) == 0
    (quick_tuning, quick_test, full) = asked
    assert (quick_tuning.worlds, quick_tuning.sequences, quick_tuning.split) == (1, 1, "tuning")
    assert (quick_test.worlds, quick_test.sequences, quick_test.split) == (1, 1, "test")
    assert full.worlds > 1 and full.split == "tuning"
