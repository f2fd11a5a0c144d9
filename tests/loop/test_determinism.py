"""Reliability of every shipped scenario (dm_control's per-seed determinism tests, MuJoCo
Menagerie's model test):

  - run twice with the same seed, in two separate processes (with different Python hash
    seeds, so that nothing may hang on set or dict-of-str order), a short episode gives
    byte-identical camera frames (front and rear, every step) and an identical report;
  - another seed changes the seeded conditions: the textures (lanekeep/world/build.py `build_spec`),
    worn markings, the roadside (shadow casters, puddles, snow) and the image effects all draw
    from the scenario seed, so every scenario's frames change;
  - every scene compiles and steps for a second with no MuJoCo warning and a finite state.

The episodes run in subprocesses started together (each loops over all scenarios and prints a
line per scenario), at a reduced render size: determinism does not depend on the image size,
and the short episodes here check no accuracy.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.world.build import build

SCENARIOS = shipped_scenarios()
SECONDS = 0.5  # 5 control steps at the shipped 0.1 s period
RENDER_SIZE = (320, 180)
ROOT = Path(__file__).resolve().parents[2]
PREFIX = "RESULT "

# One process: every shipped scenario, its seed moved by `seed_offset` (argv[1]); per scenario
# a line with the SHA-256 of each step's frames, of all frames, and the report (minus wall_s)
# as JSON text (json.dumps writes NaN as NaN, so equal reports give equal text).
WORKER = f"""
import dataclasses, hashlib, json, sys, traceback
import lanekeep
from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario, shipped_scenarios

offset = int(sys.argv[1])
for name in shipped_scenarios():
    try:
        base = load_scenario(name)
        scenario = dataclasses.replace(base, seed=base.seed + offset)
        total, steps = hashlib.sha256(), []

        def collect(result, _total_steps):
            per_camera = {{}}
            for camera in sorted(result.frames):
                frame = result.frames[camera]
                head = f"{{camera}} {{frame.shape}} {{frame.dtype}}".encode()
                per_camera[camera] = hashlib.sha256(head + frame.tobytes()).hexdigest()
                total.update(head)
                total.update(frame.tobytes())
            steps.append(per_camera)

        with Episode(scenario, render_size={RENDER_SIZE!r}) as episode:
            report = episode.run({SECONDS!r}, on_step=collect).to_dict()
        report.pop("wall_s")
        line = {{"name": name, "seed": scenario.seed, "frames": total.hexdigest(),
                 "steps": steps, "report": json.dumps(report, sort_keys=True)}}
    except Exception:
        line = {{"name": name, "error": traceback.format_exc()}}
    print({PREFIX!r} + json.dumps(line), flush=True)
"""


def _start(seed_offset: int, hash_seed: int) -> subprocess.Popen:
    env = {**os.environ, "MUJOCO_GL": "egl", "PYTHONHASHSEED": str(hash_seed)}
    return subprocess.Popen([sys.executable, "-c", WORKER, str(seed_offset)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _collect(process: subprocess.Popen) -> dict[str, dict]:
    try:
        out, err = process.communicate(timeout=600)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate()
        pytest.fail(f"episode worker timed out\n{err[-3000:]}")
    if process.returncode != 0:
        pytest.fail(f"episode worker exited with {process.returncode}\n{err[-3000:]}")
    lines = [json.loads(line[len(PREFIX):]) for line in out.splitlines()
             if line.startswith(PREFIX)]
    return {line["name"]: line for line in lines}


@pytest.fixture(scope="module")
def runs() -> dict[str, dict[str, dict]]:
    """Per run ("first", "second": the scenario's own seed; "reseeded": seed + 1), per
    scenario, what the worker printed. The three processes run at the same time."""
    processes = {"first": _start(0, hash_seed=1), "second": _start(0, hash_seed=2),
                 "reseeded": _start(1, hash_seed=3)}
    return {key: _collect(process) for key, process in processes.items()}


def _line(runs, key: str, name: str) -> dict:
    line = runs[key].get(name)
    assert line is not None, f"the {key} run printed nothing for {name}"
    assert "error" not in line, f"the {key} run of {name} failed:\n{line['error']}"
    return line


def _first_difference(a: dict, b: dict) -> str:
    """Where two runs' frames first differ: step and camera."""
    for i, (sa, sb) in enumerate(zip(a["steps"], b["steps"], strict=False)):
        for camera in sorted(set(sa) | set(sb)):
            if sa.get(camera) != sb.get(camera):
                return f"step {i}, camera {camera!r}"
    return f"step counts {len(a['steps'])} vs {len(b['steps'])}"


def _report_difference(a: str, b: str) -> str:
    ra, rb = json.loads(a), json.loads(b)
    keys = sorted(k for k in set(ra) | set(rb) if json.dumps(ra.get(k), sort_keys=True)
                  != json.dumps(rb.get(k), sort_keys=True))
    return "; ".join(f"{k}: {ra.get(k)!r} vs {rb.get(k)!r}" for k in keys)


@pytest.mark.parametrize("name", SCENARIOS)
def test_same_seed_gives_identical_frames_across_processes(runs, name):
    first, second = _line(runs, "first", name), _line(runs, "second", name)
    assert len(first["steps"]) == round(SECONDS / load_scenario(name).control_period_s)
    assert first["frames"] == second["frames"], (
        f"{name}: frames differ between two processes from {_first_difference(first, second)}")


@pytest.mark.parametrize("name", SCENARIOS)
def test_same_seed_gives_identical_metrics_across_processes(runs, name):
    first, second = _line(runs, "first", name), _line(runs, "second", name)
    assert first["report"] == second["report"], (
        f"{name}: reports differ: {_report_difference(first['report'], second['report'])}")


@pytest.mark.parametrize("name", SCENARIOS)
def test_another_seed_changes_the_frames(runs, name):
    """Every scenario's textures are drawn from its seed, so every frame changes; the
    conditions (worn paint, shadow casters, puddles, snow, rain, noise) on top of that."""
    first, reseeded = _line(runs, "first", name), _line(runs, "reseeded", name)
    assert reseeded["seed"] == first["seed"] + 1
    assert json.loads(reseeded["report"])["seed"] == first["seed"] + 1
    assert reseeded["frames"] != first["frames"], f"{name}: seed + 1 renders the same frames"
    # Already the first frames: the seeded world looks different before anything has moved.
    assert reseeded["steps"][0] != first["steps"][0], (
        f"{name}: seed + 1 first differs at {_first_difference(first, reseeded)}")


WARNINGS = {name: int(value) for name, value in mujoco.mjtWarning.__members__.items()
            if name != "mjNWARNING"}


@pytest.fixture
def mujoco_messages():
    """The text of every mju_warning raised while the test runs (compiler and engine)."""
    messages: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


@pytest.mark.parametrize("name", SCENARIOS)
def test_scene_compiles_and_steps_without_mujoco_warnings(name, mujoco_messages):
    world = build(load_scenario(name))
    for _ in range(10):  # 1 s with a mild steer and throttle
        world.step(0.05, 0.3, 0.1)
    assert world.data.time == pytest.approx(1.0)
    raised = {w: int(world.data.warning[i].number) for w, i in WARNINGS.items()
              if world.data.warning[i].number}
    assert not raised, f"{name}: MuJoCo warnings {raised}"
    assert mujoco_messages == []
    assert np.all(np.isfinite(world.data.qpos)) and np.all(np.isfinite(world.data.qvel))
