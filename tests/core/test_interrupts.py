"""Interrupted runs keep what they had: SIGTERM (a scheduler, `timeout`, `kill`) ends `run` and
`bench` as Ctrl-C does, with verified recordings, partial reports marked incomplete, and no
worker process left behind (lanekeep/core/interrupts.py)."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import small_scenario_text

from lanekeep.scenario.schema import load_scenario

BIN = Path(sys.executable).parent
pytestmark = pytest.mark.slow


LONG_S = 200.0  # an episode's simulated length: a minute or more of wall time at 320x180


def small_scenario(tmp_path: Path, name: str) -> Path:
    """clear_straight at 320x180 (fast) under another name, LONG_S long at 1.5 m/s (300 m of
    its 400 m road): an episode is still running when the signal comes, however the machine's
    speed and load place that moment (the first recording bytes land after about 2 s of wall
    time; a 20 s episode took only about 6 s)."""
    text = small_scenario_text("clear_straight", LONG_S, keep_criteria=True)
    for old, new in (('name = "clear_straight"', f'name = "{name}"'),
                     ("target_speed_mps = 15.0", "target_speed_mps = 1.5"),
                     ("\nspeed_mps = 15.0", "\nspeed_mps = 1.5")):
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    scenario = load_scenario(path)
    assert scenario.camera.width == 320 and scenario.duration_s == LONG_S
    assert scenario.start.s_m + scenario.target_speed_mps * LONG_S < scenario.road.length_m
    return path


def start(args: list[str], **kwargs) -> subprocess.Popen:
    return subprocess.Popen([str(BIN / "lanekeep"), *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "MUJOCO_GL": "egl"}, **kwargs)


def wait_for(condition, proc: subprocess.Popen, timeout_s: float = 180.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.2)


def children_of(pid: int) -> list[int]:
    """Pids whose parent is `pid` (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def verify(path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(BIN / "rerun"), "rrd", "verify", str(path)],
                          capture_output=True, text=True, timeout=120)


def test_sigterm_during_run_keeps_a_verified_recording_and_a_partial_report(tmp_path):
    scenario = small_scenario(tmp_path, "small_straight")
    rrd, report = tmp_path / "run.rrd", tmp_path / "run.json"
    proc = start(["run", str(scenario), "--record", str(rrd), "--json", str(report)])
    try:
        wait_for(lambda: rrd.exists() and rrd.stat().st_size > 100_000, proc)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    document = json.loads(report.read_text(), parse_constant=pytest.fail)
    assert document["completed"] is False and document["stop_reason"] == "interrupted"
    assert 0 < document["duration_s"] < LONG_S
    assert verify(rrd).returncode == 0


@pytest.mark.parametrize("how", ["sigterm_to_parent", "ctrl_c_to_group"])
def test_an_interrupted_bench_keeps_its_reports_and_leaves_no_worker(tmp_path, how):
    scenarios = [small_scenario(tmp_path, f"small_{i}") for i in range(3)]
    records, report = tmp_path / "rrd", tmp_path / "bench.json"
    proc = start(["bench", *map(str, scenarios), "--workers", "2", "--json", str(report),
                  "--record-dir", str(records)], start_new_session=True)
    try:
        # both workers are well into an episode: two recordings with a few steps each
        wait_for(lambda: len([p for p in records.glob("*.rrd")
                              if p.stat().st_size > 100_000]) == 2, proc)
        workers = children_of(proc.pid)
        assert workers, "no worker processes found"
        if how == "sigterm_to_parent":
            proc.send_signal(signal.SIGTERM)
        else:
            os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=150)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "bench interrupted" in err
    # the children of the exited bench are reaped (by it, or once orphaned by init) within
    # moments; an orphan left running would go on with its episode, a minute or more longer
    deadline = time.monotonic() + 10.0
    while [pid for pid in workers if alive(pid)] and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [pid for pid in workers if alive(pid)], "orphan workers"
    document = json.loads(report.read_text(), parse_constant=pytest.fail)
    stopped = [label for label, r in document.items() if not r["completed"]]
    assert len(stopped) == 2 and all(document[s]["stop_reason"] == "interrupted"
                                     for s in stopped)
    assert "small_2" not in document  # it never started: not reported as if it had run
    assert "1 not run (small_2)" in err or "1 not run" in err
    for label in stopped:
        assert verify(records / f"{label}.rrd").returncode == 0
