"""Values of one `[estimation]` key compared in the closed loop, on the tuning scenarios.

Each scenario runs once per value, full length at the shipped camera size. A choice of the
estimator's defaults is made here, and the bench then reports it on scenarios it was not
chosen on. tools/compare_estimation.py is its command line.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from statistics import mean

from lanekeep.core.workers import set_thread_counts, worker_pool
from lanekeep.tuning.scenarios import TuningInputError

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
        from lanekeep.scenario.schema import EstimationConfig

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
