"""Paper 001's Tables 3-4, scored as the paper scores them: each offset at the vehicle (the
car's own offset from the lane centre, x = 0), RMSE over every step of the drive with the value
the paper's loop carries at that step (a model without a detection keeps its last one), for
model #1, model #2, the final (MMAE) offset and the observer (the rear reference).

Ours (`EpisodeReport.sources`) scores each model's raw detection at its own look-ahead over
the steps it is valid, which is kinder to a model that fails often: the two are not mixed.
`tools/paper_tables.py` runs the paper cases over seeds and prints these beside the paper's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

# The paper's figures (its Tables 3 and 4, RMSE in cm against the ground truth).
PAPER_TABLES: dict[str, dict[str, float]] = {
    "case2_sharp_turn": {"model1": 21.12, "model2": 47.29, "final": 20.40, "observer": 13.87},
    "case4_half_shade_straight": {"model1": 48.62, "model2": 45.33, "final": 41.43,
                                  "observer": 23.35},
}
COLUMNS = ("model1", "model2", "final", "observer")


def carried(values: Sequence[float | None]) -> np.ndarray:
    """Each step's value, or the last one before it where it has none (NaN before the first):
    what a loop that keeps a variable per model would hold."""
    out = np.full(len(values), np.nan)
    last = math.nan
    for i, value in enumerate(values):
        if value is not None and math.isfinite(value):
            last = float(value)
        out[i] = last
    return out


def rmse_cm(estimates_m: np.ndarray, truth_m: np.ndarray) -> float:
    """RMSE in cm over the steps with an estimate (NaN when none has one)."""
    error = np.asarray(estimates_m, float) - np.asarray(truth_m, float)
    error = error[np.isfinite(error)]
    return float(100.0 * np.sqrt(np.mean(error**2))) if len(error) else math.nan


@dataclass
class PaperTrace:
    """One paper-mode episode, per step: the true offset at the car, each column's offset at
    the car (None where it has none this step), the selected model, and whether the step is in
    the case's event (the shade for case 1, the turn for case 2)."""

    truth_m: list[float] = field(default_factory=list)
    offsets_m: dict[str, list[float | None]] = field(
        default_factory=lambda: {c: [] for c in COLUMNS})
    selected: list[int] = field(default_factory=list)
    in_event: list[bool] = field(default_factory=list)

    def add(self, truth_m: float, offsets_m: dict[str, float | None], selected: int,
            in_event: bool) -> None:
        self.truth_m.append(float(truth_m))
        for column in COLUMNS:
            self.offsets_m[column].append(offsets_m.get(column))
        self.selected.append(int(selected))
        self.in_event.append(bool(in_event))


@dataclass(frozen=True)
class PaperRow:
    """One episode's Table 3-4 row and its pattern figures."""

    rmse_cm: dict[str, float]  # per column, over every step (carried)
    event_rmse_cm: dict[str, float]  # per column, over the event's steps only
    steps: int
    event_steps: int
    uncarried_steps: dict[str, int]  # steps before a column's first value (not scored)
    selected_share_in_event: tuple[float, float]  # share of event steps on model #1, #2
    # Share of the event's steps, and of the other steps, in which model #1 / #2 had a value
    # of its own this step (not one carried): where a model "loses the lane" (case 1).
    valid_share_in_event: tuple[float, float] = (math.nan, math.nan)
    valid_share_outside: tuple[float, float] = (math.nan, math.nan)

    def to_dict(self) -> dict:
        return {"rmse_cm": self.rmse_cm, "event_rmse_cm": self.event_rmse_cm,
                "steps": self.steps, "event_steps": self.event_steps,
                "uncarried_steps": self.uncarried_steps,
                "selected_share_in_event": list(self.selected_share_in_event),
                "valid_share_in_event": list(self.valid_share_in_event),
                "valid_share_outside": list(self.valid_share_outside)}


def paper_row(trace: PaperTrace) -> PaperRow:
    """Score one episode as the paper does (see the module docstring)."""
    truth = np.asarray(trace.truth_m, float)
    event = np.asarray(trace.in_event, bool)
    selected = np.asarray(trace.selected, int)
    rmse, event_rmse, uncarried = {}, {}, {}
    for column in COLUMNS:
        held = carried(trace.offsets_m[column])
        rmse[column] = rmse_cm(held, truth)
        event_rmse[column] = rmse_cm(held[event], truth[event]) if event.any() else math.nan
        uncarried[column] = int(np.sum(~np.isfinite(held)))
    n_event = int(event.sum())
    shares = ((float(np.mean(selected[event] == 0)), float(np.mean(selected[event] == 1)))
              if n_event else (math.nan, math.nan))
    own = {c: np.array([v is not None and math.isfinite(v) for v in trace.offsets_m[c]], bool)
           for c in ("model1", "model2")}

    def valid_share(steps: np.ndarray) -> tuple[float, float]:
        if not steps.any():
            return (math.nan, math.nan)
        return (float(own["model1"][steps].mean()), float(own["model2"][steps].mean()))

    return PaperRow(rmse, event_rmse, len(truth), n_event, uncarried, shares,
                    valid_share(event), valid_share(~event))
