"""The search: Optuna's ask/tell over the spec's dimensions, candidates run in batches through
the sweep's runners (lanekeep/sweep/run.py), each batch told back in trial order.

Why this shape:
  - reproducible: the sampler is seeded, a batch has a fixed size (`batch`, not the number of
    workers) and its results are told in trial order once the whole batch is back, so the same
    seed asks the same candidates on 2 local workers or 200 Ray CPUs;
  - resumable: the search is replayed from its seed, and every episode the output folder
    already holds (lanekeep/sweep/falsify_store.py) is read back, not run; a larger budget
    goes on where the last run stopped;
  - one trial is one candidate (parameter values) driven on every seed of the spec; its
    margin is the worst over those seeds (lanekeep/sweep/falsify_objective.py). The budget
    counts episodes: trials = budget // seeds.

Samplers: "tpe" (Optuna's TPESampler, multivariate, with the constant liar so that the trials
of one batch spread out; its first 10 trials are random) and "random" (RandomSampler: the
baseline with the same budget).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from lanekeep.sweep.falsify_spec import Dimension, FalsifySpec, table_id
from lanekeep.sweep.falsify_store import FalsifyStore
from lanekeep.sweep.run import CellResult
from lanekeep.sweep.spec import Cell

SAMPLERS = ("tpe", "random")
Execute = Callable[[list[Cell], Callable[[CellResult], None]], None]


@dataclass(frozen=True)
class Candidate:
    """One episode to run: a trial's parameter values on one seed."""

    phase: str  # "search" or "shrink"
    trial: int
    values: tuple[Any, ...]
    seed: int


@dataclass(frozen=True)
class Trial:
    number: int
    values: tuple[Any, ...]
    margin: float | None  # worst over the seeds; None when an episode raised
    seed: int  # the seed that gave the margin
    binding: str  # the criterion that set it


class Evaluator:
    """Runs candidates (each episode once: a finished one is read back from the store) and
    returns their rows in the candidates' order."""

    def __init__(self, spec: FalsifySpec, store: FalsifyStore, execute: Execute,
                 on_episode: Callable[[dict], None] | None = None) -> None:
        self.spec, self.store, self.execute = spec, store, execute
        self.on_episode = on_episode or (lambda row: None)
        self.ran = {"search": 0, "shrink": 0}  # episodes run (not read back), per phase

    def __call__(self, candidates: list[Candidate]) -> list[dict]:
        ids, todo = [], {}
        for c in candidates:
            table = self.spec.table(c.values, c.seed)
            cid = table_id(table)
            ids.append(cid)
            if self.store.finished(cid) is None and cid not in todo:
                todo[cid] = (c, Cell(cid, c.values, c.seed, table, self.spec.sweep.nominal_seed))
        for cid in ids:  # read back: counted by the progress bar all the same
            if cid not in todo:
                self.on_episode(self.store.latest(cid))

        def on_result(result: CellResult) -> None:
            if result.status == "interrupted":
                raise KeyboardInterrupt
            c, cell = todo[result.cell_id]
            self.ran[c.phase] += 1
            self.on_episode(self.store.add(cell.cell_id, c.phase, c.trial, c.values, c.seed,
                                           result))

        if todo:
            self.execute([cell for _, cell in todo.values()], on_result)
        return [self.store.latest(cid) for cid in ids]


def distribution(dim: Dimension):
    from optuna.distributions import (
        CategoricalDistribution,
        FloatDistribution,
        IntDistribution,
    )

    if dim.kind == "choice":  # by index: a choice may be an array or a table
        return CategoricalDistribution(tuple(range(len(dim.choices))))
    if dim.kind == "int":
        return IntDistribution(int(dim.low), int(dim.high))
    return FloatDistribution(dim.low, dim.high)


def value_of(dim: Dimension, param: Any) -> Any:
    """The scenario value of a sampled parameter; floats to 6 significant digits, so the
    failing files read plainly (the rounded value is the one that runs)."""
    if dim.kind == "choice":
        return dim.choices[param]
    if dim.kind == "int":
        return int(param)
    return min(dim.high, max(dim.low, float(f"{param:.6g}")))


def make_sampler(name: str, seed: int):
    import optuna

    if name == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if name == "tpe":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            return optuna.samplers.TPESampler(seed=seed, multivariate=True,
                                              constant_liar=True)
    raise ValueError(f"unknown sampler {name!r} (known: {', '.join(SAMPLERS)})")


def trial_of(number: int, values: tuple, rows: list[dict]) -> Trial:
    """A trial's margin: the worst over its seeds' episodes (None if one raised)."""
    if any(r["margin"] is None for r in rows):
        bad = next(r for r in rows if r["margin"] is None)
        return Trial(number, values, None, bad["seed"], "")
    worst = min(rows, key=lambda r: r["margin"])
    return Trial(number, values, worst["margin"], worst["seed"], worst["binding"])


def run_search(spec: FalsifySpec, evaluate: Evaluator, sampler: str, seed: int, budget: int,
               batch: int, on_batch: Callable[[list[Trial]], None] | None = None
               ) -> list[Trial]:
    """Every trial of the search, in trial order (module docstring)."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    seeds = spec.sweep.seeds
    n_trials = budget // len(seeds)
    dists = {d.key: distribution(d) for d in spec.dimensions}
    study = optuna.create_study(direction="minimize", sampler=make_sampler(sampler, seed))
    trials: list[Trial] = []
    while len(trials) < n_trials:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            asked = [study.ask(dists) for _ in range(min(batch, n_trials - len(trials)))]
        values = [tuple(value_of(d, t.params[d.key]) for d in spec.dimensions) for t in asked]
        rows = evaluate([Candidate("search", t.number, v, s)
                         for t, v in zip(asked, values, strict=True) for s in seeds])
        done = []
        for i, (t, v) in enumerate(zip(asked, values, strict=True)):
            trial = trial_of(t.number, v, rows[i * len(seeds):(i + 1) * len(seeds)])
            if trial.margin is None or not math.isfinite(trial.margin):
                study.tell(t, state=TrialState.FAIL)
            else:
                study.tell(t, trial.margin)
            done.append(trial)
        trials += done
        if on_batch is not None:
            on_batch(done)
    return trials
