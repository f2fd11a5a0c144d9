"""What a search leaves besides its table: the failing cases as scenario files, the summary,
and the plot of margin against each parameter.

A failing case's file is the candidate's whole scenario table (lanekeep/sweep/falsify_spec.py:
its length, render size and criteria included), so `lanekeep run FILE --seed S` drives the same
episode and judges it alike: exit 1, the same margin. The file's own `seed` is the base's, so
that, as in the search, the base's seed is the nominal drive and seed S (`--seed`) draws the
start and traffic as the search's cell did (lanekeep/sweep/spec.py `Cell.nominal_seed`). The
exact command is in the file's first lines and in summary.json.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lanekeep.sweep.falsify_search import Trial
from lanekeep.sweep.falsify_shrink import Shrunk
from lanekeep.sweep.falsify_spec import FalsifySpec

PLOT = "margin_vs_parameters.png"


@dataclass(frozen=True)
class Case:
    """A failing scenario written to a file."""

    path: Path
    label: str  # "worst 1", "minimal"
    trial: int
    values: tuple[Any, ...]
    seed: int
    margin: float
    binding: str

    @property
    def command(self) -> str:
        return f"lanekeep run {self.path} --seed {self.seed}"


def worst(trials: list[Trial], k: int) -> list[Trial]:
    """The `k` failing trials of lowest margin, distinct in their values, worst first."""
    failing = sorted((t for t in trials if t.margin is not None and t.margin < 0),
                     key=lambda t: (t.margin, t.number))
    out, seen = [], set()
    for t in failing:
        key = repr(t.values)
        if key not in seen:
            seen.add(key)
            out.append(t)
    return out[:k]


def write_case(spec: FalsifySpec, path: Path, label: str, trial: int, values: tuple, seed: int,
               margin: float, binding: str, how: str) -> Case:
    """A failing candidate's scenario file, headed by how it was found and how to rerun it."""
    import tomli_w

    case = Case(path, label, trial, values, seed, margin, binding)
    table = {**spec.table(values, seed), "seed": spec.sweep.nominal_seed}  # module docstring
    params = ", ".join(f"{k} = {v!r}" for k, v in zip(spec.keys, values, strict=True))
    head = [f"# {label} of `lanekeep falsify {spec.source}` ({how}): trial {trial}, "
            f"seed {seed}",
            f"# margin {margin:.4f} (binding: {binding}); parameters: {params}",
            f"# Reproduce (exit 1, the same margin): {case.command}",
            "# The whole scenario: the base's table with the parameters, duration_s and "
            "[criteria] of the search; `seed` is the base's (its nominal drive): --seed "
            "gives the drive.", ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(head) + tomli_w.dumps(table), encoding="utf-8")
    return case


def case_dict(case: Case, keys: tuple[str, ...]) -> dict:
    return {"file": str(case.path), "label": case.label, "trial": case.trial,
            "seed": case.seed, "margin": case.margin, "binding": case.binding,
            "parameters": dict(zip(keys, case.values, strict=True)), "command": case.command}


def first_failure(trials: list[Trial], seeds: int) -> int | None:
    """Episodes the search had run when its first failing trial finished (None: none)."""
    for i, t in enumerate(trials):
        if t.margin is not None and t.margin < 0:
            return (i + 1) * seeds
    return None


def summary(spec: FalsifySpec, search: dict, trials: list[Trial], cases: list[Case],
            minimal: tuple[Case, Shrunk] | None, ran: dict[str, int]) -> dict:
    margins = [t.margin for t in trials if t.margin is not None]
    best = min(trials, key=lambda t: t.margin, default=None) if margins else None
    return {
        "falsify": spec.name, "file": spec.source, "base": spec.sweep.base, **search,
        "dimensions": [{"key": d.key, "kind": d.kind, "choices": list(d.choices) or None,
                        "low": None if d.kind == "choice" else d.low,
                        "high": None if d.kind == "choice" else d.high, "base": d.base}
                       for d in spec.dimensions],
        "criteria": spec.criteria, "seeds": list(spec.sweep.seeds),
        "seconds": spec.sweep.seconds,
        "render": list(spec.sweep.render) if spec.sweep.render else None,
        "trials": len(trials), "episodes_search": len(trials) * len(spec.sweep.seeds),
        "episodes_run_now": ran,
        "episodes_raised": sum(t.margin is None for t in trials),
        "failing_trials": sum(m < 0 for m in margins),
        "first_failure_after_episodes": first_failure(trials, len(spec.sweep.seeds)),
        "best": None if best is None else {
            "trial": best.number, "margin": best.margin, "seed": best.seed,
            "binding": best.binding,
            "parameters": dict(zip(spec.keys, best.values, strict=True))},
        "worst": [case_dict(c, spec.keys) for c in cases],
        "minimal": None if minimal is None else {
            **case_dict(minimal[0], spec.keys), "needed": list(minimal[1].needed),
            "episodes": minimal[1].episodes},
    }


def plot_margins(spec: FalsifySpec, rows: list[dict], minimal: dict | None,
                 path: Path) -> Path:
    """Margin against each parameter, one panel each: search episodes (failures red), the
    shrinking's (grey), the base value (dashed), the minimal case (star), margin 0 (black)."""
    import matplotlib

    matplotlib.use("Agg")
    import json

    import matplotlib.pyplot as plt

    n = len(spec.dimensions)
    cols = min(n, 3)
    nrows = math.ceil(n / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.6 * nrows), squeeze=False,
                             sharey=True, layout="constrained")
    rows = [r for r in rows if r.get("margin") is not None]
    for ax, dim in zip(axes.flat, spec.dimensions, strict=False):
        labels = [c if isinstance(c, str) else json.dumps(c, sort_keys=True) for c in dim.choices]

        def x_of(value, dim=dim, labels=labels):
            if dim.kind != "choice":
                return value
            text = value if isinstance(value, str) else json.dumps(value, sort_keys=True)
            return labels.index(text) if text in labels else -1  # -1: the base value

        for phase, style in (("search", "o"), ("shrink", "x")):
            sel = [r for r in rows if r["phase"] == phase]
            xs = [x_of(_value(r[dim.key])) for r in sel]
            ys = [r["margin"] for r in sel]
            colour = ["grey" if phase == "shrink" else ("C3" if y < 0 else "C0") for y in ys]
            ax.scatter(xs, ys, c=colour, marker=style, s=22, alpha=0.8,
                       label=f"{phase} ({len(sel)})")
        ax.axhline(0.0, color="k", linewidth=0.8)
        base_x = x_of(dim.base)
        ax.axvline(base_x, color="k", linestyle="--", linewidth=0.8, alpha=0.6)
        if minimal is not None:
            ax.scatter([x_of(minimal["parameters"][dim.key])], [minimal["margin"]],
                       marker="*", s=160, c="gold", edgecolors="k", zorder=5, label="minimal")
        if dim.kind == "choice":
            ticks = list(range(len(labels))) + ([-1] if base_x == -1 else [])
            ax.set_xticks(ticks, labels + (["base"] if base_x == -1 else []), rotation=20,
                          ha="right", fontsize=8)
        ax.set_xlabel(dim.key)
        ax.grid(True, alpha=0.3)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("margin (< 0: fails)")
    axes.flat[0].legend(fontsize=8)
    fig.suptitle(f"{spec.name}: margin of each episode against each parameter "
                 f"(dashed: the base's value)", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _value(cell: Any) -> Any:
    """A table cell back to its value (arrays were stored as JSON text)."""
    import json

    if isinstance(cell, str) and cell[:1] in "[{":
        return json.loads(cell)
    return cell
