"""Replay one drive's estimator inputs through the estimator with other settings: seconds a
value where `python -m lanekeep.tuning.estimation` needs minutes, for the estimator's choices
only.

    MUJOCO_GL=egl python -m lanekeep.tuning.replay record DIR [SCENARIO ...]
    MUJOCO_GL=egl python -m lanekeep.tuning.replay record DIR fog --seed 2
    python -m lanekeep.tuning.replay compare DIR reference_std_m=0.05,0.03

`record` drives each scenario once in the closed loop (default: every tuning scenario; shipped
ones only with --allow-scored, as lanekeep.tuning.estimation) and keeps, per step, what the
estimator was given (the front detections, the rear reference, the dead-reckoned ego-motion)
and the true offset at the output's look-ahead, scoring only; one pickle per scenario in DIR
(about 1 MB). `--seed` records another seed than the file's; the bench scores each shipped
scenario at its file's seed only, so a shipped scenario at any other seed is unscored data and
allowed. `compare` runs a fresh `LaneEstimator` over each recording once per value of one
`EstimatorSettings` key and prints the output's RMSE against the best own track's, to 0.1 mm,
and per value the mean and the count of episodes where the output is above its best track.

Open loop: the car drove the recorded line whatever the replayed output says, so a change that
would have steered it elsewhere is not scored for that; confirm a choice with
lanekeep.tuning.estimation (closed loop) and the bench. The recordings are pickles: load only
your own.

tools/replay_estimation.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import os
import pickle
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from statistics import mean

import numpy as np

from lanekeep.tuning.estimation import typed_value
from lanekeep.tuning.scenarios import (
    TuningInputError,
    add_scenario_arguments,
    own_seed,
    select_scenarios,
)


def path_stem(name: str, seed: int | None) -> str:
    """A recording's name: the scenario's, with the seed when it is not the file's."""
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
        estimator = episode.driver.estimator
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


def load_recordings(folder: Path, key: str) -> list[dict]:
    """Every recording (*.pkl) in `folder`, sorted by name; TuningInputError if there is none
    or a file is not a recording whose settings have `key`."""
    paths = sorted(folder.glob("*.pkl"))
    if not paths:
        raise TuningInputError(f"no recordings (*.pkl) in {folder}")
    recordings = []
    for path in paths:
        try:
            with path.open("rb") as f:
                data = pickle.load(f)
            getattr(data["settings"], key)
            data["steps"], data["names"], data["reference_x_m"]  # noqa: B018 - a recording's keys
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError, KeyError,
                TypeError) as err:
            raise TuningInputError(f"{path} is not a recording of this tool ({err!r})") from None
        recordings.append(data)
    return recordings


def setting_values(recordings: list[dict], key: str, text: str) -> list[object]:
    """The comma-separated `text` as values of `key`, typed as the recorded loop had it;
    TuningInputError if that type is not a number, a string or a flag, or a value is not
    one."""
    current = getattr(recordings[0]["settings"], key)
    kind = type(current)
    if kind not in (bool, int, float, str):
        raise TuningInputError(f"{key} is {current!r} in the recordings; only a number, a "
                               "string or true/false is set here")
    try:
        return [typed_value(kind, v) for v in text.split(",")]
    except (KeyError, ValueError):
        raise TuningInputError(f"{key} cannot be {text!r} (a {kind.__name__} here)") from None


def replay(data: dict, **settings) -> tuple[np.ndarray, np.ndarray]:
    """The output's and each track's offset error (m, NaN where none) per step, with the
    recorded settings changed by `settings`."""
    from lanekeep.estimators.lane_estimator import LaneEstimator
    from lanekeep.geometry.lane_poly import LanePoly

    estimator = LaneEstimator(data["names"], dataclasses.replace(data["settings"], **settings),
                              data["reference_x_m"])
    output, tracks = [], []
    for step in data["steps"]:
        out = estimator.update(step["detections"], step["reference"], step["ego"])
        truth = step["truth_m"]
        output.append(np.nan if out.offset_m is None else out.offset_m - truth)
        tracks.append([np.nan if out.tracked[n] is None
                       else float(LanePoly.of(out.tracked[n]).offset_m(out.offset_x_m)) - truth
                       for n in data["names"]])
    return np.asarray(output), np.asarray(tracks)


def rmse_cm(errors_m: np.ndarray) -> float:
    return float(np.sqrt(np.nanmean(np.square(errors_m))) * 100.0)


def compare(recordings: list[dict], key: str, values: list[object]) -> list[tuple]:
    """(scenario, value, output RMSE, best track RMSE, its model) per recording and value.
    ValueError from the estimator's own checks (an unknown mode, a bad number)."""
    rows = []
    for data in recordings:
        for value in values:
            output, tracks = replay(data, **{key: value})
            scores = [rmse_cm(tracks[:, i]) for i in range(tracks.shape[1])]
            best = int(np.argmin(scores))
            rows.append((data["scenario"], value, rmse_cm(output), scores[best],
                         data["names"][best]))
    return rows


@dataclass(frozen=True)
class ReplaySummary:
    """One value over the recordings: the mean of (output - best track), cm, and the count of
    recordings where the output is above its best track."""

    value: object
    output_minus_track: float
    above: int


def summarise(rows: Sequence[tuple], values: Sequence[object]) -> list[ReplaySummary]:
    """Per value, in order, its `ReplaySummary` over `compare`'s rows."""
    out = []
    for value in values:
        mine = [r for r in rows if r[1] == value]
        out.append(ReplaySummary(value, mean(r[2] - r[3] for r in mine),
                                 sum(r[2] > r[3] for r in mine)))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="drive scenarios and keep the estimator's inputs")
    rec.add_argument("out", type=Path)
    add_scenario_arguments(rec)
    rec.add_argument("--seed", type=int, help="record this seed instead of the file's")
    cmp = sub.add_parser("compare", help="replay recordings with values of one setting")
    cmp.add_argument("recordings", type=Path, help="a directory of `record`'s pickles")
    cmp.add_argument("setting", help="KEY=VALUE,VALUE... of the estimator's settings")
    args = parser.parse_args(argv)
    if args.command == "record":
        if args.seed is not None and args.seed < 0:
            parser.exit(2, f"error: --seed must be >= 0, got {args.seed}\n")
        unscored = args.seed is not None and all(
            own_seed(s) != args.seed for s in args.scenarios)
        try:
            scenarios = select_scenarios(args.scenarios,
                                         allow_scored=args.allow_scored or unscored)
        except TuningInputError as err:
            parser.exit(2, f"error: {err}\n")
        if args.out.exists() and not args.out.is_dir():
            parser.exit(2, f"error: {args.out} exists and is not a directory\n")
        args.out.mkdir(parents=True, exist_ok=True)
        os.environ.setdefault("MUJOCO_GL", "egl")
        for scenario in scenarios:
            print(record(scenario, args.out, args.seed), flush=True)
        return 0
    from lanekeep.estimators.lane_estimator import EstimatorSettings

    key, _, text = args.setting.partition("=")
    if key not in {f.name for f in dataclasses.fields(EstimatorSettings)} or not text:
        parser.exit(2, f"error: {args.setting!r} is not KEY=VALUE,... of EstimatorSettings\n")
    try:
        recordings = load_recordings(args.recordings, key)
        values = setting_values(recordings, key, text)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    try:
        rows = compare(recordings, key, values)
    except ValueError as err:  # the estimator's own checks (an unknown mode, a bad number)
        parser.exit(2, f"error: {key}: {err}\n")
    for name, value, output, track, model in rows:
        print(f"{name:<36} {value!s:<10} output {output:7.4f}  best track {track:7.4f} "
              f"({model})  {output - track:+.4f}")
    print(f"\nper value of {key} over {len(recordings)} recordings (cm, open loop):")
    for s in summarise(rows, values):
        print(f"  {s.value!s:<10} output - best track: mean {s.output_minus_track:+.4f}"
              f"; above it in {s.above}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
