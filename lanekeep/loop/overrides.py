"""Swapping a scenario's detectors and controller for an episode (the `--front-detectors`,
`--reference-detector` and `--controller` options of `run` and `bench`): a built-in name, an
entry point's name or an import path `package.module:Class` (lanekeep/core/plugins.py), so a
user's own detector or controller runs on the shipped scenarios without editing a file."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from lanekeep.scenario.schema import Scenario


@dataclass(frozen=True)
class PluginOverrides:
    """The command line's choices; None keeps the scenario file's."""

    front_detectors: tuple[str, ...] | None = None
    reference_detector: str | None = None
    controller: str | None = None

    def check(self) -> None:
        """Import each name given (ConfigError naming the option and the name)."""
        from lanekeep.control.registry import check_controller
        from lanekeep.detectors.registry import check_detector

        for name in self.front_detectors or ():
            check_detector(name, "--front-detectors")
        if self.reference_detector is not None:
            check_detector(self.reference_detector, "--reference-detector")
        if self.controller is not None:
            check_controller(self.controller, "--controller")

    def apply(self, scenario: Scenario) -> Scenario:
        """`scenario` with these choices in place of its own."""
        est = scenario.estimation
        if self.front_detectors is not None:
            est = dataclasses.replace(est, front_detectors=self.front_detectors)
        if self.reference_detector is not None:
            est = dataclasses.replace(est, reference_detector=self.reference_detector)
        control = scenario.control
        if self.controller is not None:
            control = dataclasses.replace(control, controller=self.controller)
        return dataclasses.replace(scenario, estimation=est, control=control)
