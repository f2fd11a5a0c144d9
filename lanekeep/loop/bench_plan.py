"""`lanekeep bench` as a library: which episodes a bench runs, checked before any worker
starts, and how their reports are grouped into one document per label.

A bench plans once (`bench_scenarios`, `check_bench`, `plan_jobs`): the scenarios as each
episode will run them (the mode first, then the command line's plug-ins), a job per scenario
and seed, and with `single_model` a job per front model alone. After the run the reports are
grouped by label over their seeds (`bench_documents`, lanekeep/report/seed_summary.py) and
compared with a baseline (`regression`, lanekeep/report/regression.py).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from lanekeep.core.config_io import ConfigError
from lanekeep.loop.checks import check_scenario
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.loop.runner import BenchJob
from lanekeep.scenario.schema import Scenario
from lanekeep.scoring.metrics import EpisodeReport

Seeds = dict[str, list[int | None]]  # scenario name -> its seeds (None: the file's own)


class BaselineMismatch(ValueError):
    """The baseline and this bench cannot be paired (the gate's exit code 2)."""


@dataclass(frozen=True)
class BenchPlan:
    """The episodes of a bench: the scenarios' main loops first, then their model-only ones."""

    main_jobs: list[BenchJob]
    jobs: list[BenchJob]
    many: bool  # a scenario runs on several seeds: labels carry the seed, tables the spread

    @property
    def main_labels(self) -> list[str]:
        return [job.episode_label for job in self.main_jobs]


def bench_scenarios(names: Sequence[str], mode: str | None, plugins: PluginOverrides
                    ) -> dict[str, Scenario]:
    """Each scenario as its episodes will run it: the mode first (its own front models), then
    the command line's plug-ins; a bad name fails here, before anything runs."""
    from lanekeep.loop.paper_mode import with_mode
    from lanekeep.scenario.schema import load_scenario

    return {name: plugins.apply(with_mode(load_scenario(name), mode)) for name in names}


def check_bench(scenarios: dict[str, Scenario], seeds: Seeds, seconds: float | None) -> None:
    """Every scenario on every seed it runs (shadow casters stand where the seed puts them),
    before any worker starts: ScenarioError or ConfigError naming the file."""
    for name, scenario in scenarios.items():
        for seed in seeds[name]:
            check_scenario(scenario if seed is None else
                           dataclasses.replace(scenario, seed=seed), seconds)


def plan_jobs(names: Sequence[str], scenarios: dict[str, Scenario], seeds: Seeds,
              mode: str | None, plugins: PluginOverrides, single_model: bool) -> BenchPlan:
    """A job per scenario named and seed, and with `single_model` one per front model
    alone."""
    many = any(len(s) > 1 for s in seeds.values())
    main_jobs = [BenchJob(name, seed, mode, plugins=plugins, seed_in_label=many)
                 for name in names for seed in seeds[name]]
    jobs = list(main_jobs)
    if single_model:
        jobs += [BenchJob(name, seed, mode, (model,), plugins, many) for name in names
                 for model in scenarios[name].estimation.front_detectors
                 for seed in seeds[name]]
    return BenchPlan(main_jobs, jobs, many)


def control_period_s(scenarios: dict[str, Scenario]) -> float | None:
    """The control period every scenario shares (None: they differ), for the progress bar."""
    periods = {scenario.control_period_s for scenario in scenarios.values()}
    return periods.pop() if len(periods) == 1 else None


def file_margins(scenarios: dict[str, Scenario]) -> dict:
    """Each scenario's own `[criteria] margins`, keyed "LABEL:METRIC" as `--margin` keys a
    scenario's; ConfigError naming the file for a metric that does not exist."""
    from lanekeep.report.compare import parse_margins

    out = {}
    for name, scenario in scenarios.items():
        try:
            out.update(parse_margins([f"{name}:{t}" for t in scenario.criteria.margins]))
        except ValueError as err:
            raise ConfigError(scenario.source or name, "criteria.margins", str(err)) from None
    return out


def bench_documents(jobs: list[BenchJob], reports: list[EpisodeReport],
                    scenarios: dict[str, Scenario], plugins: PluginOverrides,
                    weights: str | None, mode: str | None, single_model: bool
                    ) -> dict[str, dict]:
    """`bench --json`: one document per label over its seeds (lanekeep/report/seed_summary.py),
    the scenarios first, then their model-only loops."""
    from lanekeep.report.seed_summary import summarise

    first_job: dict[str, BenchJob] = {}
    by_label: dict[str, list] = {}
    for job, report in zip(jobs, reports, strict=True):
        first_job.setdefault(job.label, job)
        by_label.setdefault(job.label, []).append(report)
    overrides = {**dataclasses.asdict(plugins), "weights": weights}
    documents = {}
    for label, runs in by_label.items():
        job = first_job[label]
        single = None
        if job.front_detectors is None and single_model:
            single = {"+".join(other.front_detectors): by_label[other_label]
                      for other_label, other in first_job.items()
                      if other.front_detectors is not None and other.scenario == job.scenario}
        documents[label] = summarise(label, runs, scenarios[job.scenario],
                                     overrides=overrides, mode=mode, single_model=single)
    return documents


def main_documents(plan: BenchPlan, documents: dict[str, dict]) -> list[dict]:
    """The scenarios' own documents (no model-only loop), once each, in the plan's order."""
    return [documents[label] for label in dict.fromkeys(job.label for job in plan.main_jobs)]


def regression(baseline: dict, documents: dict, main_docs: list[dict],
               scenarios: dict[str, Scenario], margins: dict):
    """The regression gate of this bench against `baseline` (lanekeep/report/regression.py),
    the scenarios' own margins under the command line's; BaselineMismatch when the two cannot
    be paired."""
    import json

    from lanekeep.report.json_io import dumps
    from lanekeep.report.regression import regression_gate

    mains = json.loads(dumps({d["label"]: documents[d["label"]] for d in main_docs}))
    two_mode = {name: s.criteria.bad_episode_fused_rmse_m for name, s in scenarios.items()
                if s.criteria.bad_episode_fused_rmse_m is not None}
    try:
        return regression_gate(baseline, mains, margins={**file_margins(scenarios), **margins},
                               two_mode=two_mode)
    except ValueError as err:
        raise BaselineMismatch(str(err)) from err
