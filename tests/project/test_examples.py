"""The scripts in examples/ run as a user runs them (a subprocess from the repository root),
at a reduced camera size and for a few seconds, and print what they promise."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
QUICK = ["--seconds", "3", "--size", "320x180"]


def _run(script: str, *args: str) -> str:
    done = subprocess.run([sys.executable, str(ROOT / "examples" / script), *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no warnings, no EGL tracebacks at exit
    return done.stdout


def test_run_episode_prints_the_report():
    out = _run("run_episode.py", "clear_straight", *QUICK)
    assert "RMSE" in out and "fused" in out  # the report's table
    assert re.search(r"clear_straight: 30 steps, 0 lane departures", out), out


def test_my_detector_runs_as_a_front_model():
    out = _run("my_detector.py", *QUICK)
    m = re.search(r"bright_paint\s+offset RMSE\s+([\d.]+) cm, valid on (\d+)%", out)
    assert m, out
    rmse_cm, valid = float(m.group(1)), int(m.group(2))
    assert valid > 0 and rmse_cm < 10.0  # it found the lane, and about where it is
    assert "lane departures: 0" in out


def test_gym_loop_keeps_the_lane_to_the_end():
    pytest.importorskip("gymnasium")
    out = _run("gym_loop.py", "clear_straight", *QUICK)
    m = re.search(r"(\d+) steps, return ([\d.]+) \(at most \d+\), ended by the scenario's", out)
    assert m, out
    steps, ret = int(m.group(1)), float(m.group(2))
    assert steps == 30 and ret > 0.8 * steps  # 3 s of 0.1 s periods, all of them acted on
