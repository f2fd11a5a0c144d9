"""The tuning tools are modules of the package: `python -m lanekeep.tuning.<module>` runs each
command line from any working directory (an install, not only a clone), tools/ keeps a short
script per command that calls the same `main`, and the tuning scenarios are package data found
with importlib.resources."""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from importlib import resources
from pathlib import Path

import pytest

from lanekeep.tuning.roll_coupling import CURVES, default_scenarios
from lanekeep.tuning.scenarios import select_scenarios, tuning_dir, tuning_scenarios

ROOT = Path(__file__).resolve().parents[2]
# tools/ script -> the lanekeep.tuning module that holds its command line
SCRIPTS = {
    "calibrate_criteria.py": "criteria_calibration",
    "compare_estimation.py": "estimation",
    "contact_sheet.py": "contact_sheet",
    "drive_video.py": "drive_video",
    "measure_antialiasing.py": "antialiasing",
    "measure_detector_noise.py": "detector_noise",
    "measure_roll_coupling.py": "roll_coupling",
    "measure_shade.py": "shade_ratio",
    "realism_report.py": "realism_report",
    "replay_estimation.py": "replay",
    "trace_estimation.py": "trace",
    "tune_lanenet_decode.py": "decode_priors",
    "tune_real.py": "real_accuracy",
    "tuning/detector_replay.py": "detector_replay",
}
PACKAGE = "lanekeep.tuning.scenario_files"


@pytest.mark.parametrize("module", sorted(SCRIPTS.values()))
def test_python_m_runs_the_command_line(module, tmp_path):
    """`--help` exits 0 and prints the usage, run away from the clone's root."""
    done = subprocess.run([sys.executable, "-m", f"lanekeep.tuning.{module}", "--help"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith("usage: ")


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_each_tools_script_calls_its_modules_main(script):
    """A script is a docstring, `from lanekeep.tuning.<module> import main` and the call."""
    tree = ast.parse((ROOT / "tools" / script).read_text(encoding="utf-8"))
    imports = [(n.module, [a.name for a in n.names]) for n in ast.walk(tree)
               if isinstance(n, ast.ImportFrom)]
    assert imports == [(f"lanekeep.tuning.{SCRIPTS[script]}", ["main"])]
    assert not [n for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)]


def test_the_tuning_scenarios_are_package_resources():
    files = sorted(f.name for f in resources.files(PACKAGE).iterdir()
                   if f.name.endswith(".toml"))
    assert len(files) >= 4
    assert [p.name for p in tuning_scenarios()] == files
    assert tuning_dir() == Path(str(resources.files(PACKAGE)))
    assert sorted(Path(a).name for a in select_scenarios([])) == files
    assert all(Path(p).is_file() for p in default_scenarios())
    assert {Path(p).stem for p in default_scenarios()} == set(CURVES)


def test_pyproject_installs_the_tuning_scenarios():
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    setuptools = setuptools["tool"]["setuptools"]
    assert PACKAGE in setuptools["packages"]
    assert setuptools["package-data"][PACKAGE] == ["*.toml"]


def test_no_tuning_scenario_is_left_in_tools():
    assert not list((ROOT / "tools" / "tuning").glob("*.toml"))
