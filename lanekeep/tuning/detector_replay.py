"""Replay recorded camera frames through the classical detectors and score them: a quick,
open-loop way to tune the detectors on the tuning scenarios (never on the shipped ones).

    MUJOCO_GL=egl python -m lanekeep.tuning.detector_replay record \\
        lanekeep/tuning/scenario_files/tune_traffic_lead_van_three_lanes.toml \\
        /tmp/lk/replay/van --seconds 25
    python -m lanekeep.tuning.detector_replay score /tmp/lk/replay/van
    python -m lanekeep.tuning.detector_replay score /tmp/lk/replay/van --config my.toml
    python -m lanekeep.tuning.detector_replay score /tmp/lk/replay/shade --steps 128:209 \\
        --per-step errors.json

`record` drives the scenario once (a scenario file, e.g. a tuning scenario's, or a shipped
scenario's name) and keeps every front and rear frame (raw uint8 .npy, about 2.8 MB a frame)
with the true offsets at each detector's look-ahead, taken from the pose the frame was rendered
at (scoring only: the detectors still see the frames alone). The car is steered on the true lane
centre plus a slow sinusoidal wander (WANDER_M, WANDER_PERIOD_S): the recording is data for
tuning the detectors, and a loop that a fooled detector drove out of its lane would leave
nothing to tune on; `--closed-loop` records the loop's own drive instead. `score` runs a fresh
hough and sliding_window on the front frames and sliding_window on the rear (a classical
reference the loop can select with `reference_detector`; its default is LaneNet, which this
tool does not score) in order, so the sliding windows' memory of the last fit plays as in
the loop, and
prints per detector: RMSE and the 95th percentile of the offset error, the share of valid
frames, the share of gross errors (over GROSS_M) and the detector's time per frame. `--config
FILE` scores a candidate detectors TOML (a partial file: the rest keeps the tuned defaults)
instead of the shipped one; `--steps FIRST:END` scores a stretch of the drive (a shaded one),
`--per-step FILE` writes each detector's error at every step scored. A replay scores
detection, not control.

tools/tuning/detector_replay.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

WANDER_M = 0.35  # the recorded drive's lateral wander about the lane centre (amplitude)
WANDER_PERIOD_S = 9.0
GROSS_M = 0.3  # an error this large is a wrong line (a vehicle edge, a shadow), not noise
JOBS = (("hough", "front"), ("sliding_window", "front"), ("sliding_window", "rear"))


def record(scenario_path: str, out: Path, seconds: float | None, closed_loop: bool = False
           ) -> None:
    """Drive the scenario; save its frames and the true offsets per step."""
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_offsets

    scenario = load_scenario(scenario_path)
    out.mkdir(parents=True, exist_ok=True)
    with Episode(scenario) as episode:
        steps = episode.total_steps if seconds is None else int(round(seconds / episode.dt_s))
        cams = episode.simulator.rig.cameras
        x_refs = lookaheads(cams)
        frames = {name: np.lib.format.open_memmap(
            out / f"{name}.npy", mode="w+", dtype=np.uint8,
            shape=(steps, cams[name].height, cams[name].width, 3)) for name in ("front", "rear")}
        truth = np.zeros((steps, len(x_refs)))
        lane = scenario.road.ego_lane
        for i in range(steps):
            pose = episode.world.car.pose()  # the pose the frames are rendered at
            step = episode.step(None if closed_loop else truth_action(episode, pose, i))
            for name in frames:
                frames[name][i] = step.frames[name]
            truth[i] = lane_offsets(episode.world.road, *pose, lane, list(x_refs.values()))
        for f in frames.values():
            f.flush()
    np.save(out / "truth.npy", truth)
    # A file's absolute path (a shipped name as it is): `score` may run from another folder.
    where = Path(scenario_path)
    name = str(where.resolve()) if where.is_file() else scenario_path
    (out / "meta.json").write_text(json.dumps({"scenario": name,
                                               "x_refs": x_refs, "steps": steps}))


def truth_action(episode, pose, index: int) -> tuple[float, float]:
    """(steer, throttle) that follow the true lane centre, offset by the wander."""
    from lanekeep.scoring.truth import lane_centre_fit

    centre, _ = lane_centre_fit(episode.world.road, *pose, episode.scenario.road.ego_lane)
    x_ctrl = episode.scenario.estimation.control_lookahead_m
    wander = WANDER_M * np.sin(2.0 * np.pi * index * episode.dt_s / WANDER_PERIOD_S)
    offset = -float(centre[0] + centre[1] * x_ctrl) - wander
    speed = episode.world.car.speed_mps()
    steer = episode.driver.controller.steering(offset, speed, curvature_1pm=float(2.0 * centre[2]))
    return steer, episode.driver.controller.speed(speed)


def lookaheads(cameras) -> dict[str, float]:
    """Look-ahead of each job's detector, keyed 'detector@camera'."""
    from lanekeep.detectors.registry import make_detector

    return {f"{d}@{c}": float(make_detector(d, cameras[c]).x_ref) for d, c in JOBS}


def step_range(spec: str | None, steps: int) -> range:
    """The recorded steps `--steps FIRST:END` names (END exclusive, either side may be left
    out, as a Python slice: `128:209` is the shaded stretch of tune_right_turn_shade_bumps);
    None: every step. Raises ValueError naming the problem."""
    if spec is None:
        return range(steps)
    first, sep, end = spec.partition(":")
    try:
        if not sep:
            raise ValueError
        bounds = slice(int(first) if first else None, int(end) if end else None)
    except ValueError:
        raise ValueError(f"--steps must be FIRST:END (step indices), got {spec!r}") from None
    chosen = range(steps)[bounds]
    if len(chosen) == 0:
        raise ValueError(f"--steps {spec} holds none of the recording's {steps} steps")
    return chosen


def summarise(errors: list[float | None], wall_s: float) -> dict[str, float]:
    """A detector's statistics over its per-step offset errors (m; None = no valid lane)."""
    found = [e for e in errors if e is not None]
    err = np.abs(np.asarray(found)) if found else np.zeros(1)
    n = max(len(errors), 1)
    return {
        "rmse_cm": float(np.sqrt(np.mean(err ** 2)) * 100),
        "p95_cm": float(np.percentile(err, 95) * 100),
        "max_cm": float(err.max() * 100),
        "valid_pct": 100.0 * len(found) / n,
        "gross_pct": 100.0 * float(np.sum(err > GROSS_M)) / n,
        "ms": 1000.0 * wall_s / n,
    }


def score(folder: Path, config_path: str | Path | None = None, steps: str | None = None,
          per_step: dict[str, list[float | None]] | None = None) -> dict[str, dict[str, float]]:
    """Per-detector error statistics over a recording (see the module docstring), with the
    detectors' thresholds from `config_path` (None: the shipped detectors.toml), so that a
    candidate tuning is scored without editing the shipped file. `steps` (`step_range`)
    scores a stretch of the drive only (the detectors still start at its first step);
    `per_step`, when given, receives each detector's offset error at every scored step (m,
    None where it had no lane), to find where a detector fails."""
    from lanekeep.detectors.config import load_config
    from lanekeep.detectors.registry import make_detector
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.world.build import build

    meta = json.loads((folder / "meta.json").read_text())
    scenario = load_scenario(meta["scenario"])
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, scenario.camera.width,
                                                  scenario.camera.height)) as rig:
        cameras = dict(rig.cameras)
    truth = np.load(folder / "truth.npy")
    chosen = step_range(steps, len(truth))
    frames = {name: np.load(folder / f"{name}.npy", mmap_mode="r") for name in ("front", "rear")}
    config = load_config(config_path)
    out = {}
    for j, (name, cam) in enumerate(JOBS):
        detector = make_detector(name, cameras[cam], config=config)
        errors: list[float | None] = []
        wall = 0.0
        for i in chosen:
            frame = np.ascontiguousarray(frames[cam][i])
            t0 = time.perf_counter()
            est = detector.detect(frame)
            wall += time.perf_counter() - t0
            errors.append(float(est.offset_m - truth[i, j]) if est.valid else None)
        out[f"{name}@{cam}"] = summarise(errors, wall)
        if per_step is not None:
            per_step[f"{name}@{cam}"] = errors
    return out


def main(argv: list[str] | None = None) -> int:
    from lanekeep.detectors.config import load_config

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("scenario")
    rec.add_argument("out", type=Path)
    rec.add_argument("--seconds", type=float)
    rec.add_argument("--closed-loop", action="store_true",
                     help="record the loop's own drive, not the truth-steered one")
    sco = sub.add_parser("score")
    sco.add_argument("folders", type=Path, nargs="+")
    sco.add_argument("--config", type=Path,
                     help="detectors TOML to score (default: the shipped detectors.toml)")
    sco.add_argument("--steps", metavar="FIRST:END",
                     help="score only these recorded steps (END exclusive; e.g. 128:209)")
    sco.add_argument("--per-step", type=Path, metavar="FILE",
                     help="write each detector's offset error at every scored step (JSON, "
                          "metres, null where it had no lane), per folder")
    args = parser.parse_args(argv)
    if args.command == "score" and args.config is not None:
        try:  # a bad candidate file: one line, before any frame is scored
            load_config(args.config)
        except (OSError, ValueError) as err:
            parser.exit(2, f"detector_replay: error: {err}\n")
    if args.command == "record":
        record(args.scenario, args.out, args.seconds, args.closed_loop)
        return 0
    if args.command == "score":
        for folder in args.folders:  # every problem before any frame is scored
            problem = _unreadable(folder, args.steps)
            if problem:
                parser.exit(2, f"detector_replay: error: {problem}\n")
    per_step: dict[str, dict[str, list[float | None]]] = {}
    for folder in args.folders:
        print(folder.name)
        per_step[str(folder)] = {}
        for job, s in score(folder, args.config, args.steps, per_step[str(folder)]).items():
            print(f"  {job:22s} rmse {s['rmse_cm']:6.1f} cm  p95 {s['p95_cm']:6.1f}  max "
                  f"{s['max_cm']:6.1f}  valid {s['valid_pct']:5.1f}%  gross "
                  f"{s['gross_pct']:5.1f}%  {s['ms']:5.1f} ms")
    if args.per_step is not None:
        args.per_step.write_text(json.dumps({"steps": args.steps, "folders": per_step}))
    return 0


def _unreadable(folder: Path, steps: str | None) -> str:
    """Why a folder is no recording, or its `--steps` none of its steps ('' when fine)."""
    try:
        count = len(np.load(folder / "truth.npy", mmap_mode="r"))
        json.loads((folder / "meta.json").read_text())
    except (OSError, ValueError) as err:
        return f"{folder}: not a recording ({err})"
    try:
        step_range(steps, count)
    except ValueError as err:
        return f"{folder}: {err}"
    return ""


if __name__ == "__main__":
    sys.exit(main())
