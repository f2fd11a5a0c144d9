"""Why the fused output beats or loses to a model: per-model bias, spread and MMAE weight.

    MUJOCO_GL=egl .venv/bin/python tools/trace_estimation.py night [--output fused]

Runs one episode (a shipped scenario's name or a scenario file) and prints, per front model,
its own track's offset error at the output's look-ahead (RMSE, mean = bias, standard
deviation), its curvature error, and its mean MMAE probability; then the same errors of the
output and of the rear reference. A model whose track is biased but whose probability is high
points at a reference that shares the model's error (the same detector on the rear camera); a
small probability left to a biased model shows how much of its bias reaches the output.
Truth is read here for scoring only, as in `lanekeep run`.
"""

from __future__ import annotations

import argparse
import dataclasses
import os

import numpy as np


def trace(scenario_arg: str, output: str | None) -> dict[str, np.ndarray]:
    """Per step: each model's offset and curvature errors and probability, the output's and
    the reference's errors (NaN where a source had nothing)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    from lanekeep.episode import Episode, track_source
    from lanekeep.ground_truth import lane_offsets
    from lanekeep.scenario import load_scenario

    scenario = load_scenario(scenario_arg)
    if output is not None:
        scenario = dataclasses.replace(
            scenario, estimation=dataclasses.replace(scenario.estimation, output=output))
    columns: dict[str, list[float]] = {}

    def add(key: str, value: float | None) -> None:
        columns.setdefault(key, []).append(np.nan if value is None else float(value))

    with Episode(scenario) as episode:
        road = episode.world.road

        def on_step(result, _total) -> None:
            x, y, _ = result.sensed_pose
            s, _ = road.local_coordinates(np.array([[x, y]]))
            curvature = float(road.curvature_at(float(np.ravel(s)[0])))
            for i, name in enumerate(episode.front):
                track = result.tracked[name]
                offset = result.track_offsets_m[name]
                add(track_source(name), None if offset is None
                    else offset - result.truth_output_m)
                add(f"{name}:curvature", None if track is None
                    else 2.0 * track[2] - curvature)
                add(f"{name}:p", result.probabilities[i])
            centre = result.output_centre
            add("fused", None if result.output_offset_m is None
                else result.output_offset_m - result.truth_output_m)
            add("fused:curvature", None if centre is None else 2.0 * centre[2] - curvature)
            truth = lane_offsets(road, *result.sensed_pose, scenario.road.ego_lane,
                                 [result.reference_x_m])[0]
            add("reference", None if result.reference_m is None
                else result.reference_m - float(truth))

        episode.run(on_step=on_step)
    return {k: np.asarray(v) for k, v in columns.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", help="a shipped scenario's name or a scenario file")
    parser.add_argument("--output", choices=("select", "fused", "precision"),
                        help="[estimation] output instead of the scenario's")
    args = parser.parse_args(argv)
    columns = trace(args.scenario, args.output)
    print(f"{'source':<24}{'RMSE cm':>9}{'bias cm':>9}{'std cm':>8}"
          f"{'curv. RMSE 1e-3/m':>19}{'mean p':>8}")
    sources = [k for k in columns if k.endswith(":track")] + ["fused", "reference"]
    for key in sources:
        err = columns[key]
        model = key.removesuffix(":track")
        curv = columns.get(f"{model}:curvature")
        p = columns.get(f"{model}:p")
        print(f"{key:<24}{100 * np.sqrt(np.nanmean(err ** 2)):9.2f}"
              f"{100 * np.nanmean(err):9.2f}{100 * np.nanstd(err):8.2f}"
              f"{'-' if curv is None else f'{1000 * np.sqrt(np.nanmean(curv ** 2)):.2f}':>19}"
              f"{'' if p is None else f'{np.mean(p):8.3f}'}")


if __name__ == "__main__":
    main()
