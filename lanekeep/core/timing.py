"""Wall time per stage of the closed loop, summed over steps: what `lanekeep perf` reports.

The episode always runs with a clock (a `perf_counter` call per stage, well under a
microsecond) so that the timed loop is the loop users run, not an instrumented copy of it.

    clock.start()              # at the top of a step
    ...render...
    clock.lap("render_front")  # time since the previous lap (or start) goes to that stage
"""

from __future__ import annotations

import time


class StageClock:
    """Accumulates the wall time between consecutive laps under each lap's stage name."""

    def __init__(self) -> None:
        self.totals_s: dict[str, float] = {}
        self.steps = 0
        self._last = time.perf_counter()

    def start(self) -> None:
        """A new step begins now (time before this is nobody's)."""
        self.steps += 1
        self._last = time.perf_counter()

    def lap(self, stage: str) -> None:
        """The time since the previous lap was spent in `stage`."""
        now = time.perf_counter()
        self.totals_s[stage] = self.totals_s.get(stage, 0.0) + (now - self._last)
        self._last = now

    def share(self, own_s: dict[str, float]) -> None:
        """The time since the previous lap went to stages that ran side by side (each took
        `own_s[stage]` on its own thread): each gets a share of that wall time in proportion
        to its own, so the stages still add up to the step's wall time."""
        now = time.perf_counter()
        wall, total = now - self._last, sum(own_s.values())
        for stage, own in own_s.items():
            share = wall * own / total if total > 0 else wall / len(own_s)
            self.totals_s[stage] = self.totals_s.get(stage, 0.0) + share
        self._last = now

    def reset(self) -> None:
        """Forget everything measured so far (e.g. after warm-up steps)."""
        self.totals_s.clear()
        self.steps = 0

    def mean_ms(self) -> dict[str, float]:
        """Mean milliseconds per step for each stage, in the order stages were first seen."""
        n = max(self.steps, 1)
        return {name: 1000.0 * total / n for name, total in self.totals_s.items()}
