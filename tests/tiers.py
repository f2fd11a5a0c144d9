"""Which closed-loop claims run in README's test command (CI) and which only with `-m full`.

A full-resolution closed loop costs 20-120 s on a 2-core machine. CI keeps a few of them, one
per regime the loop must handle (a straight and a curve, the paper's sharp turn, night,
traffic); the claims over every shipped scenario and over seeds are the `full` tier, run with
`pytest -m full -n auto` before a default, a detector or the loop changes (README, Testing).
"""

from __future__ import annotations

from collections.abc import Iterable

import pytest

# The shipped scenarios whose closed loop CI drives at full resolution.
CI_SCENARIOS = frozenset({"clear_straight", "clear_curve", "case2_sharp_turn", "night",
                          "highway_cut_in"})


def full_unless(values: Iterable[object], kept: Iterable[object]) -> list[object]:
    """`values` as parameters, each not in `kept` marked `full` (left out of CI's run)."""
    kept = set(kept)
    return [v if v in kept else pytest.param(v, marks=pytest.mark.full) for v in values]
