"""The minimal failing case: the worst failure, each parameter moved back toward the base
scenario's value as far as the failure holds.

Why: a failure at 22 m/s in heavy rain with a car close ahead says little until one knows
which of those it needs. One parameter at a time, in the spec's order, the episode is run with
the parameter at the base value and part of the way there (LEVELS, one batch, so they run in
parallel); the furthest level that still fails is kept. A choice parameter has one level: the
base value itself. The episodes run on the failing trial's worst seed and are counted apart
from the search's budget (`Evaluator.ran["shrink"]`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from lanekeep.sweep.falsify_search import Candidate, Evaluator, Trial
from lanekeep.sweep.falsify_spec import Dimension, FalsifySpec

LEVELS = (1.0, 0.5)  # share of the way from the failing value back to the base's


@dataclass(frozen=True)
class Shrunk:
    values: tuple[Any, ...]
    margin: float
    seed: int
    binding: str
    needed: tuple[str, ...]  # parameters that could not go back to the base value
    episodes: int  # episodes this shrinking asked for (run or read back)


def toward(dim: Dimension, value: Any, level: float) -> Any:
    """`value` moved `level` of the way to the base value (a choice jumps at level 1 only)."""
    if level == 1.0 or dim.kind == "choice":
        return dim.base
    moved = value + level * (dim.base - value)
    if dim.kind == "int":
        return int(round(moved))
    return float(f"{moved:.6g}")


def shrink(spec: FalsifySpec, evaluate: Evaluator, failing: Trial) -> Shrunk:
    """The smallest change from the base that still fails, found from `failing` (module
    docstring)."""
    values = list(failing.values)
    margin, binding, asked = failing.margin, failing.binding, 0
    for i, dim in enumerate(spec.dimensions):
        if values[i] == dim.base:
            continue
        tries = list(dict.fromkeys(
            toward(dim, values[i], level) for level in
            (LEVELS[:1] if dim.kind == "choice" else LEVELS)))
        tries = [v for v in tries if v != values[i]]
        candidates = [Candidate("shrink", failing.number,
                                tuple(v if j == i else values[j] for j in range(len(values))),
                                failing.seed) for v in tries]
        rows = evaluate(candidates)
        asked += len(candidates)
        for value, row in zip(tries, rows, strict=True):  # furthest back first
            if row["margin"] is not None and row["margin"] < 0:
                values[i], margin, binding = value, row["margin"], row["binding"]
                break
    needed = tuple(d.key for d, v in zip(spec.dimensions, values, strict=True) if v != d.base)
    return Shrunk(tuple(values), margin, failing.seed, binding, needed, asked)

