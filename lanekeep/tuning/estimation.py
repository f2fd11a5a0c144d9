"""Compare values of one `[estimation]` key in the closed loop, on the tuning scenarios.

    MUJOCO_GL=egl python -m lanekeep.tuning.estimation output=select,fused

Runs every tuning scenario (lanekeep/tuning/scenario_files/*.toml, which `lanekeep bench` does
not score) once per value, full length at the shipped camera size, and prints per episode the
MMAE output's offset RMSE, the best front model's own track (like for like), the car's maximum
lateral error and the rear reference's RMSE; then per value the mean of (output - best track)
and the sum of the car maxima. A choice of the estimator's defaults is made here, and the bench
then reports it on scenarios it was not chosen on. Shipped scenarios are refused (as by
`python -m lanekeep.tuning.detector_noise`) unless --allow-scored is given.

tools/compare_estimation.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from statistics import mean

from lanekeep.core.workers import set_thread_counts, worker_pool
from lanekeep.tuning.scenarios import TuningInputError, add_scenario_arguments, select_scenarios

BOOLEANS = {"true": True, "false": False}


def typed_value(kind: type, value: str) -> object:
    """A value of the command line as the key's type: a number key's is a number, a flag's
    is true or false (`bool("false")` would be True)."""
    if kind is bool:
        return BOOLEANS[value]
    return kind(value) if kind in (int, float) else value


@dataclass(frozen=True)
class Setting:
    """One `[estimation]` key and the values (as typed on the command line) to compare."""

    key: str
    values: tuple[str, ...]

    @classmethod
    def parse(cls, text: str) -> Setting:
        """`KEY=VALUE,VALUE...`; TuningInputError if the key is not one of `[estimation]` or a
        value is not of its type."""
        from lanekeep.scenario.estimation import EstimationConfig

        key, _, values = text.partition("=")
        if key not in {f.name for f in dataclasses.fields(EstimationConfig)} or not values:
            raise TuningInputError(f"{text!r} is not KEY=VALUE,... of [estimation]")
        kind = type(getattr(EstimationConfig(), key))
        for value in values.split(","):
            try:
                typed_value(kind, value)
            except (KeyError, ValueError):
                raise TuningInputError(f"{key} cannot be {value!r}") from None
        return cls(key, tuple(values.split(",")))


@dataclass(frozen=True)
class EpisodeResult:
    """One episode's offset errors (cm): the MMAE output's RMSE, the best front model's own
    track's (like for like) and which model that is, the car's maximum lateral error and the
    rear reference's RMSE."""

    scenario: str
    value: str
    output_cm: float
    best_track_cm: float
    best_model: str
    car_max_cm: float
    reference_cm: float


def run_one(job: tuple[str, str, str]) -> EpisodeResult:
    """One episode of scenario `job[0]` with `[estimation]` key `job[1]` set to `job[2]`."""
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
    return EpisodeResult(scenario.name, value, report.sources["fused"].rmse_cm, tracks[best],
                         best, report.car_max_cm, report.sources["reference"].rmse_cm)


def run_all(scenarios: Sequence[str], setting: Setting, workers: int
            ) -> Iterator[EpisodeResult]:
    """Every scenario with every value, in that order, `workers` episodes at a time (Ctrl-C
    reaches the workers)."""
    jobs = [(path, setting.key, value) for path in scenarios for value in setting.values]
    with worker_pool(workers, initializer=set_thread_counts) as pool:
        yield from pool.map(run_one, jobs)


@dataclass(frozen=True)
class ValueSummary:
    """One value over the scenarios (cm): the mean of (output - best track), the sum and the
    worst of the car maxima."""

    value: str
    output_minus_track: float
    car_max_sum: float
    car_max_worst: float


def summarise(results: Sequence[EpisodeResult], values: Sequence[str]) -> list[ValueSummary]:
    """Per value, in order, its `ValueSummary`."""
    out = []
    for value in values:
        mine = [r for r in results if r.value == value]
        out.append(ValueSummary(value, mean(r.output_cm - r.best_track_cm for r in mine),
                                sum(r.car_max_cm for r in mine),
                                max(r.car_max_cm for r in mine)))
    return out


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line; exits 2 on a bad setting or a shipped scenario without
    --allow-scored."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("setting",
                        help="KEY=VALUE,VALUE... of [estimation] (strings, numbers, true/false)")
    add_scenario_arguments(parser)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    try:
        args.setting = Setting.parse(args.setting)
        args.scenarios = select_scenarios(args.scenarios, allow_scored=args.allow_scored)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    setting: Setting = args.setting
    results = []
    for r in run_all(args.scenarios, setting, args.workers):
        results.append(r)
        print(f"{r.scenario:<36} {r.value:<10} output {r.output_cm:6.3f}  best track "
              f"{r.best_track_cm:6.3f} ({r.best_model})  car max {r.car_max_cm:5.1f}  "
              f"reference {r.reference_cm:5.2f}", flush=True)
    print(f"\nper value of {setting.key} over {len(args.scenarios)} scenarios (cm):")
    for s in summarise(results, setting.values):
        print(f"  {s.value:<10} output - best track: mean {s.output_minus_track:+.3f}; "
              f"car max: sum {s.car_max_sum:.1f}, worst {s.car_max_worst:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
