"""Compare values of one `[estimation]` key in the closed loop, on the tuning scenarios.

    MUJOCO_GL=egl .venv/bin/python tools/compare_estimation.py output=select,fused

Runs every tuning scenario (tools/tuning/*.toml, which `lanekeep bench` does not score) once
per value, full length at the shipped camera size, and prints per episode the MMAE output's
offset RMSE, the best front model's own track (like for like), the car's maximum lateral error
and the rear reference's RMSE; then per value the mean of (output - best track) and the sum of
the car maxima. A choice of the estimator's defaults is made here, and the bench then reports
it on scenarios it was not chosen on. Shipped scenarios are refused (as by
tools/measure_detector_noise.py) unless --allow-scored is given.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from statistics import mean

TOOLS = Path(__file__).resolve().parent


def _noise_tool():
    """tools/measure_detector_noise.py: its tuning-scenario list and shipped-scenario guard."""
    spec = importlib.util.spec_from_file_location("measure_detector_noise",
                                                  TOOLS / "measure_detector_noise.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _init_worker(threads: int) -> None:
    """One worker's thread counts, before EGL, OpenCV or torch start (as `lanekeep bench`)."""
    os.environ["LP_NUM_THREADS"] = os.environ["OMP_NUM_THREADS"] = str(threads)
    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    cv2.setNumThreads(threads)


def run_one(job: tuple[str, str, str]) -> tuple[str, str, float, float, str, float, float]:
    """(scenario, value, output RMSE, best track RMSE, its model, car max, reference RMSE), cm."""
    path, key, value = job
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario(path)
    typed = typed_value(type(getattr(scenario.estimation, key)), value)
    estimation = dataclasses.replace(scenario.estimation, **{key: typed})
    with Episode(dataclasses.replace(scenario, estimation=estimation)) as episode:
        report = episode.run()
    tracks = {k: v.rmse_cm for k, v in report.sources.items() if k.endswith(":track")}
    best = min(tracks, key=tracks.get)
    return (scenario.name, value, report.sources["fused"].rmse_cm, tracks[best], best,
            report.car_max_cm, report.sources["reference"].rmse_cm)


BOOLEANS = {"true": True, "false": False}


def typed_value(kind: type, value: str) -> object:
    """A value of the command line as the key's type: a number key's is a number, a flag's
    is true or false (`bool("false")` would be True)."""
    if kind is bool:
        return BOOLEANS[value]
    return kind(value) if kind in (int, float) else value


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("setting",
                        help="KEY=VALUE,VALUE... of [estimation] (strings, numbers, true/false)")
    parser.add_argument("scenarios", nargs="*",
                        help="scenario names or files (default: every file in tools/tuning/)")
    parser.add_argument("--allow-scored", action="store_true",
                        help="allow shipped scenarios, which `lanekeep bench` scores")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    key, _, values = args.setting.partition("=")
    from lanekeep.scenario.schema import EstimationConfig

    if key not in {f.name for f in dataclasses.fields(EstimationConfig)} or not values:
        parser.exit(2, f"error: {args.setting!r} is not KEY=VALUE,... of [estimation]\n")
    args.key, args.values = key, values.split(",")
    kind = type(getattr(EstimationConfig(), key))
    for value in args.values:
        try:
            typed_value(kind, value)
        except (KeyError, ValueError):
            parser.exit(2, f"error: {key} cannot be {value!r}\n")
    guard = ["--allow-scored"] if args.allow_scored else []
    args.scenarios = _noise_tool().parse_args([*args.scenarios, *guard]).scenarios
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    jobs = [(path, args.key, value) for path in args.scenarios for value in args.values]
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    rows = []
    with ProcessPoolExecutor(args.workers, initializer=_init_worker,
                             initargs=(threads,)) as pool:
        for row in pool.map(run_one, jobs):
            rows.append(row)
            name, value, output, track, model, car_max, reference = row
            print(f"{name:<36} {value:<10} output {output:6.3f}  best track {track:6.3f} "
                  f"({model})  car max {car_max:5.1f}  reference {reference:5.2f}", flush=True)
    print(f"\nper value of {args.key} over {len(args.scenarios)} scenarios (cm):")
    for value in args.values:
        mine = [r for r in rows if r[1] == value]
        print(f"  {value:<10} output - best track: mean {mean(r[2] - r[3] for r in mine):+.3f}; "
              f"car max: sum {sum(r[5] for r in mine):.1f}, worst {max(r[5] for r in mine):.1f}")


if __name__ == "__main__":
    main()
