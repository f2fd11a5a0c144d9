"""Paper mode on a scenario: `[estimation] mode = "paper"` in a scenario, or `--mode paper` on
`lanekeep run` / `lanekeep bench`. What the mode changes in the car is the driver's
(lanekeep/driver/paper_mode.py, which says what differs from our default loop and why); here
only how a scenario is put into the mode."""

from __future__ import annotations

from dataclasses import replace

from lanekeep.scenario.estimation import DEFAULT_FRONT_DETECTORS
from lanekeep.scenario.schema import Scenario


def with_mode(scenario: Scenario, mode: str | None) -> Scenario:
    """The scenario with its estimation mode set (None keeps the file's). Front models that
    are the old mode's defaults become the new mode's (the paper's loop runs its two models);
    models a scenario names are kept."""
    if mode is None:
        return scenario
    est = scenario.estimation
    own_default = est.front_detectors == DEFAULT_FRONT_DETECTORS[est.mode]
    front = None if own_default else est.front_detectors
    return replace(scenario, estimation=replace(est, mode=mode, front_detectors=front))
