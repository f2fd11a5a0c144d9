"""Replay one drive's estimator inputs through the estimator with other settings: seconds a
value where tools/compare_estimation.py needs minutes, for the estimator's choices only.

    MUJOCO_GL=egl .venv/bin/python tools/replay_estimation.py record DIR [SCENARIO ...]
    MUJOCO_GL=egl .venv/bin/python tools/replay_estimation.py record DIR fog --seed 2
    .venv/bin/python tools/replay_estimation.py compare DIR reference_std_m=0.05,0.03

`record` drives each scenario once in the closed loop (default: every tuning scenario; shipped
ones only with --allow-scored, as compare_estimation) and keeps, per step, what the estimator
was given (the front detections, the rear reference, the dead-reckoned ego-motion) and the true
offset at the output's look-ahead, scoring only; one pickle per scenario in DIR (about 1 MB).
`--seed` records another seed than the file's; the bench scores each shipped scenario at its
file's seed only, so a shipped scenario at any other seed is unscored data and allowed.
`compare` runs a fresh `LaneEstimator` over each recording once per value of one
`EstimatorSettings` key and prints the output's RMSE against the best own track's, to 0.1 mm,
and per value the mean and the count of episodes where the output is above its best track.

Open loop: the car drove the recorded line whatever the replayed output says, so a change that
would have steered it elsewhere is not scored for that; confirm a choice with
compare_estimation (closed loop) and the bench. The recordings are pickles: load only your own.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import importlib.util
import os
import pickle
from pathlib import Path
from statistics import mean

import numpy as np

TOOLS = Path(__file__).resolve().parent


def _compare_tool():
    """tools/compare_estimation.py: the tuning-scenario guard and its value typing."""
    spec = importlib.util.spec_from_file_location("compare_estimation",
                                                  TOOLS / "compare_estimation.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def path_stem(name: str, seed: int | None) -> str:
    return name if seed is None else f"{name}_seed{seed}"


def record(scenario_arg: str, out: Path, seed: int | None = None) -> Path:
    """Drive one scenario (at `seed`, None: the file's); pickle its estimator's inputs and
    the truth per step."""
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario(scenario_arg)
    if seed is not None:
        scenario = dataclasses.replace(scenario, seed=seed)
    steps: list[dict] = []
    with Episode(scenario) as episode:
        estimator = episode.estimator
        update = estimator.update

        def recording_update(detections, reference, ego, **timing):
            steps.append({"detections": copy.deepcopy(detections),
                          "reference": copy.deepcopy(reference), "ego": ego})
            return update(detections, reference, ego, **timing)

        estimator.update = recording_update
        episode.run(on_step=lambda result, _t: steps[-1].update(truth_m=result.truth_output_m))
        data = {"scenario": path_stem(scenario.name, seed), "names": list(estimator.names),
                "settings": estimator.settings, "reference_x_m": estimator.reference_x_m,
                "steps": steps}
    path = out / f"{path_stem(scenario.name, seed)}.pkl"
    with path.open("wb") as f:
        pickle.dump(data, f)
    return path


def _own_seed(scenario_arg: str) -> int | None:
    """The seed a scenario's file gives it (the one the bench scores); None if it will not
    load (the guard then says why)."""
    from lanekeep.scenario.schema import ScenarioError, load_scenario

    try:
        return load_scenario(scenario_arg).seed
    except ScenarioError:
        return None


def replay(data: dict, **settings) -> tuple[np.ndarray, np.ndarray]:
    """The output's and each track's offset error (m, NaN where none) per step, with the
    recorded settings changed by `settings`."""
    from lanekeep.detectors.base import poly_eval
    from lanekeep.estimators.lane_estimator import LaneEstimator

    estimator = LaneEstimator(data["names"], dataclasses.replace(data["settings"], **settings),
                              data["reference_x_m"])
    output, tracks = [], []
    for step in data["steps"]:
        out = estimator.update(step["detections"], step["reference"], step["ego"])
        truth = step["truth_m"]
        output.append(np.nan if out.offset_m is None else out.offset_m - truth)
        tracks.append([np.nan if out.tracked[n] is None
                       else -float(poly_eval(out.tracked[n], out.offset_x_m)) - truth
                       for n in data["names"]])
    return np.asarray(output), np.asarray(tracks)


def rmse_cm(errors_m: np.ndarray) -> float:
    return float(np.sqrt(np.nanmean(np.square(errors_m))) * 100.0)


def compare(recordings: list[dict], key: str, values: list[object]) -> list[tuple]:
    """(scenario, value, output RMSE, best track RMSE, its model) per recording and value."""
    rows = []
    for data in recordings:
        for value in values:
            output, tracks = replay(data, **{key: value})
            scores = [rmse_cm(tracks[:, i]) for i in range(tracks.shape[1])]
            best = int(np.argmin(scores))
            rows.append((data["scenario"], value, rmse_cm(output), scores[best],
                         data["names"][best]))
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="drive scenarios and keep the estimator's inputs")
    rec.add_argument("out", type=Path)
    rec.add_argument("scenarios", nargs="*", help="default: every file in tools/tuning/")
    rec.add_argument("--allow-scored", action="store_true",
                     help="allow shipped scenarios, which `lanekeep bench` scores")
    rec.add_argument("--seed", type=int, help="record this seed instead of the file's")
    cmp = sub.add_parser("compare", help="replay recordings with values of one setting")
    cmp.add_argument("recordings", type=Path, help="a directory of `record`'s pickles")
    cmp.add_argument("setting", help="KEY=VALUE,VALUE... of the estimator's settings")
    args = parser.parse_args(argv)
    if args.command == "record":
        if args.seed is not None and args.seed < 0:
            parser.exit(2, f"error: --seed must be >= 0, got {args.seed}\n")
        unscored = args.seed is not None and all(
            _own_seed(s) != args.seed for s in args.scenarios)
        guard = ["--allow-scored"] if args.allow_scored or unscored else []
        tool = _compare_tool()
        scenarios = tool._noise_tool().parse_args([*args.scenarios, *guard]).scenarios
        if args.out.exists() and not args.out.is_dir():
            parser.exit(2, f"error: {args.out} exists and is not a directory\n")
        args.out.mkdir(parents=True, exist_ok=True)
        os.environ.setdefault("MUJOCO_GL", "egl")
        for scenario in scenarios:
            print(record(scenario, args.out, args.seed), flush=True)
        return
    from lanekeep.estimators.lane_estimator import EstimatorSettings

    key, _, text = args.setting.partition("=")
    fields = {f.name for f in dataclasses.fields(EstimatorSettings)}
    paths = sorted(args.recordings.glob("*.pkl"))
    if key not in fields or not text:
        parser.exit(2, f"error: {args.setting!r} is not KEY=VALUE,... of EstimatorSettings\n")
    if not paths:
        parser.exit(2, f"error: no recordings (*.pkl) in {args.recordings}\n")
    recordings = []
    for path in paths:
        try:
            with path.open("rb") as f:
                data = pickle.load(f)
            getattr(data["settings"], key)
            data["steps"], data["names"], data["reference_x_m"]  # noqa: B018 - a recording's keys
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError, KeyError,
                TypeError) as err:
            parser.exit(2, f"error: {path} is not a recording of this tool ({err!r})\n")
        recordings.append(data)
    kind = type(getattr(recordings[0]["settings"], key))  # as the recorded loop had it
    if kind not in (bool, int, float, str):
        parser.exit(2, f"error: {key} is {getattr(recordings[0]['settings'], key)!r} in the "
                       "recordings; only a number, a string or true/false is set here\n")
    try:
        typed_value = _compare_tool().typed_value
        values = [typed_value(kind, v) for v in text.split(",")]
    except (KeyError, ValueError):
        parser.exit(2, f"error: {key} cannot be {text!r} (a {kind.__name__} here)\n")
    try:
        rows = compare(recordings, key, values)
    except ValueError as err:  # the estimator's own checks (an unknown mode, a bad number)
        parser.exit(2, f"error: {key}: {err}\n")
    for name, value, output, track, model in rows:
        print(f"{name:<36} {value!s:<10} output {output:7.4f}  best track {track:7.4f} "
              f"({model})  {output - track:+.4f}")
    print(f"\nper value of {key} over {len(recordings)} recordings (cm, open loop):")
    for value in values:
        mine = [r for r in rows if r[1] == value]
        print(f"  {value!s:<10} output - best track: mean {mean(r[2] - r[3] for r in mine):+.4f}"
              f"; above it in {sum(r[2] > r[3] for r in mine)}")


if __name__ == "__main__":
    main()
