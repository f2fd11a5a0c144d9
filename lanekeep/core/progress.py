"""Progress bars of `run` and `bench` (tqdm): steps done, elapsed and remaining time.

Why one module: both commands want the same bar, drawn on stderr only when stderr is a
terminal, so that a CI log or a redirected file holds no carriage-return noise.
"""

from __future__ import annotations

import sys

from tqdm import tqdm


def step_bar(total: int, label: str, enabled: bool | None = None) -> tqdm:
    """A bar over `total` control steps; `enabled` None: only when stderr is a terminal."""
    if enabled is None:
        enabled = sys.stderr.isatty()
    return tqdm(total=total, desc=label, unit="step", file=sys.stderr, disable=not enabled,
                dynamic_ncols=True, leave=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} steps "
                           "[{elapsed}<{remaining}, {rate_fmt}]")


def set_progress(bar: tqdm, done: int, total: int | None = None) -> None:
    """Move `bar` to `done` steps (of a `total` that may have changed: an episode that ended
    early, off the road, takes its remaining steps off the bench's total)."""
    if total is not None and total != bar.total:
        bar.total = total
    if done != bar.n:
        bar.update(done - bar.n)
