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
# clear_curve with the front camera this test was sized on, the paper's pose, on five seeds:
# in issue #59's world (2026-11-29) three 3 s drives at 320x180 no longer resolve a 2 cm shift
# (dashcam: fused +1.08 cm [-0.12, +5.21]; paper's pose: +0.92 [-0.02, +3.15]); five with the
# paper's pose do (+0.87 [+0.10, +2.24]). The gate is what is tested here, not the camera.
SMALL = ["--seconds", "3", "--size", "320x180", "--quiet", "--workers", "1",
         "--set", "camera.preset=paper"]
FRONT = "hough,sliding_window,examples.sabotage:{}"


@pytest.fixture(scope="module")
def baseline(tmp_path_factory):
    path = tmp_path_factory.mktemp("gate") / "base.json"
    assert main(["bench", "clear_curve", "--seeds", "5", *SMALL,
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
    assert list(document) == ["clear_curve"] and len(document["clear_curve"]["seeds"]) == 5
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


def test_a_scenarios_own_margins_key_it_and_a_bad_one_is_refused(tmp_path):
    from lanekeep.core.config_io import ConfigError
    from lanekeep.loop.bench_plan import file_margins
    from lanekeep.scenario.schema import load_scenario

    base = load_scenario("clear_curve")
    text = Path(base.source).read_text().replace(
        "max_fused_rmse_m = 0.10", 'max_fused_rmse_m = 0.10\nmargins = ["car_max_cm=2,10%"]')
    path = tmp_path / "noisy.toml"
    path.write_text(text)
    margins = file_margins({"noisy": load_scenario(str(path))})
    assert set(margins) == {"noisy:car_max_cm"}
    assert (margins["noisy:car_max_cm"].absolute, margins["noisy:car_max_cm"].relative) == \
        (2.0, 0.1)
    with pytest.raises(ConfigError, match=r"criteria.margins: 'car max 2 cm': expected"):
        load_scenario(_write(
            tmp_path / "spaces.toml", text.replace("car_max_cm=2,10%", "car max 2 cm")))
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("car_max_cm=2,10%", "car_speed_cm=2"))
    with pytest.raises(ConfigError, match=r"bad.toml: criteria.margins: .*car_speed_cm=2"):
        file_margins({"bad": load_scenario(str(bad))})


def _write(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)
