"""`lanekeep bench --baseline` and `--write-baseline` (lanekeep/report/regression.py): the same
loop through a wrapper that changes nothing passes the gate, bit for bit; LaneNet's boundaries
moved 2 cm fail it, naming the scenario; bad input is one line, exit 2."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from lanekeep.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
SMALL = ["--seconds", "3", "--size", "320x180", "--quiet", "--workers", "1"]
FRONT = "hough,sliding_window,examples.sabotage:{}"


@pytest.fixture(scope="module")
def baseline(tmp_path_factory):
    path = tmp_path_factory.mktemp("gate") / "base.json"
    assert main(["bench", "clear_curve", "--seeds", "3", *SMALL,
                 "--write-baseline", str(path)]) == 0
    return path


@pytest.fixture
def examples_importable(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))  # examples/ is no installed package
    yield
    sys.modules.pop("examples.sabotage", None)


@pytest.mark.slow
def test_a_wrapper_that_changes_nothing_passes_and_a_2_cm_shift_fails(
        baseline, examples_importable, capsys):
    document = json.loads(baseline.read_text())
    assert list(document) == ["clear_curve"] and len(document["clear_curve"]["seeds"]) == 3
    capsys.readouterr()
    code = main(["bench", "--baseline", str(baseline), *SMALL,
                 "--front-detectors", FRONT.format("ShamLaneNet")])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "on the baseline's seeds" in out
    row = [line for line in out.splitlines() if line.startswith("clear_curve  ")][-1]  # gate
    assert row.split()[1:4] == ["+0.00", "[+0.00,", "+0.00]"] and row.split()[4] == "e"
    assert "regression gate: PASS" in out
    code = main(["bench", "--baseline", str(baseline), *SMALL,
                 "--front-detectors", FRONT.format("ShiftedLaneNet")])
    out = capsys.readouterr().out
    assert code == 1, out
    assert "regression gate: FAIL" in out and "  clear_curve: fused.rmse_cm +" in out


@pytest.mark.parametrize(("args", "message"), [
    (["--seeds", "3"], "--baseline: runs the baseline's own seeds: drop --seed and --seeds"),
    (["no_such_scenario"], "--baseline: the baseline has no scenario no_such_scenario"),
])
def test_bad_baseline_use_is_one_line(tmp_path, capsys, args, message):
    base = tmp_path / "base.json"
    base.write_text(json.dumps({"clear_curve": {"schema_version": 2, "seeds": [1],
                                                "episodes": [{"seed": 1}]}}))
    code = main(["bench", "--baseline", str(base), *args])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err


def test_a_missing_baseline_file_is_one_line(tmp_path, capsys):
    code = main(["bench", "--baseline", str(tmp_path / "nope.json")])
    err = capsys.readouterr().err
    assert code == 2 and "nope.json: no such file" in err and len(err.strip().splitlines()) == 1
