"""Progress of `run` and `bench` (tqdm): steps done, elapsed and remaining time.

Why one module: both commands want the same feedback on stderr. On a terminal it is tqdm's bar,
redrawn in place; elsewhere (a CI log, `2> file`, a pipe) a redrawn bar would be carriage-return
noise and silence would look like a hang, so the same tqdm counter prints a plain line every
LINE_INTERVAL_S seconds instead: simulated seconds (or steps) done, wall time and the time left.
`--quiet` turns both off.
"""

from __future__ import annotations

import sys

from tqdm import tqdm

LINE_INTERVAL_S = 5.0  # seconds between two progress lines when stderr is no terminal


class ProgressLines(tqdm):
    """tqdm's counter, rate and throttling (`mininterval`), shown as whole lines: one per
    `LINE_INTERVAL_S` and a last one when it closes, nothing redrawn or cleared."""

    def __init__(self, *args, step_s: float | None = None, **kwargs) -> None:
        self.step_s = step_s  # simulated seconds per step; None: counted in steps
        self._shown: tuple[int, int | None] | None = None  # (n, total) of the last line
        super().__init__(*args, **kwargs)

    def line(self) -> str:
        """"bench: 12.0/40.0 s simulated (30%), wall 0:25, about 0:58 left"."""
        n, total, elapsed = self.n, self.total or 0, self.format_dict["elapsed"]
        if self.step_s is not None:
            done = f"{n * self.step_s:.1f}/{total * self.step_s:.1f} s simulated"
        else:
            done = f"{n}/{total} steps"
        share = f" ({100.0 * n / total:.0f}%)" if total else ""
        wall = f"{self.desc}: {done}{share}, wall {self.format_interval(elapsed)}"
        if total and n >= total:
            return wall
        left = self.format_interval(elapsed * (total - n) / n) if n else "?"
        return f"{wall}, about {left} left"

    def display(self, msg: str | None = None, pos: int | None = None) -> bool:
        if msg is not None:  # tqdm clearing its line: a log has nothing to clear
            return False
        self.fp.write(self.line() + "\n")
        self.fp.flush()
        self._shown = (self.n, self.total)
        return True

    def close(self) -> None:
        # Where it ended, unless that was the last line shown. The total counts too: an
        # episode that ends early shrinks it, and its steps may all have been shown before
        # the shrink arrived (how the lines fall depends on the machine's speed).
        if not self.disable and (self.n, self.total) != self._shown:
            self.display()
        super().close()


def step_bar(total: int, label: str, enabled: bool | None = None,
             step_s: float | None = None) -> tqdm:
    """Progress over `total` control steps of `step_s` simulated seconds each.

    `enabled` None: a bar when stderr is a terminal, else a line every LINE_INTERVAL_S
    seconds; True: the bar wherever stderr goes; False: nothing (`--quiet`, bench workers).
    """
    if enabled is None and not sys.stderr.isatty():
        return ProgressLines(total=total, desc=label, unit="step", file=sys.stderr,
                             leave=False, mininterval=LINE_INTERVAL_S,
                             maxinterval=LINE_INTERVAL_S, step_s=step_s)
    return tqdm(total=total, desc=label, unit="step", file=sys.stderr, disable=enabled is False,
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
