"""One drive's estimator inputs recorded once and replayed through the estimator with other
settings: seconds a value where the closed loop (`lanekeep.tuning.estimation`) needs minutes,
for the estimator's choices only.

A recording keeps, per step, what the estimator was given (the front detections, the rear
reference, the dead-reckoned ego-motion) and the true offset at the output's look-ahead, for
scoring only. Open loop: the car drove the recorded line whatever the replayed output says, so
a change that would have steered it elsewhere is not scored for that. The recordings are
pickles: load only your own.
"""

from __future__ import annotations

import copy
import dataclasses
import pickle
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from statistics import mean

import numpy as np

from lanekeep.tuning.estimation import typed_value
from lanekeep.tuning.scenarios import TuningInputError


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
