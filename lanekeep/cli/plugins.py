"""`run` and `bench` options that swap the scenario's detectors and controller for an episode:
`--front-detectors`, `--reference-detector`, `--controller`. Each takes a built-in name, an
entry point's name or an import path `package.module:Class` (lanekeep/core/plugins.py), so a user's
own detector or controller runs on the shipped scenarios without editing a file.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.schema import Scenario, ScenarioError


@dataclass(frozen=True)
class PluginOverrides:
    """The command line's choices; None keeps the scenario file's."""

    front_detectors: tuple[str, ...] | None = None
    reference_detector: str | None = None
    controller: str | None = None

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> PluginOverrides:
        """Read the options and import what they name: a bad or empty name is a ConfigError
        naming the option."""
        front = getattr(args, "front_detectors", None)
        names = None
        if front is not None:
            names = tuple(n.strip() for n in front.split(","))
            if not all(names):
                raise ConfigError("", "--front-detectors",
                                  f"an empty detector name in {front!r}")
        for option, value in (("--reference-detector", getattr(args, "reference_detector", None)),
                              ("--controller", getattr(args, "controller", None))):
            if value is not None and not value.strip():
                raise ConfigError("", option, "must name one")
        overrides = cls(names, getattr(args, "reference_detector", None),
                        getattr(args, "controller", None))
        overrides.check()
        return overrides

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


def check_plugins(scenario: Scenario) -> None:
    """Import every detector and controller `scenario` names (a bad one fails here, before an
    episode starts): ScenarioError naming the file and key, e.g.
    "clear_curve.toml: estimation.front_detectors[1]: detector 'mod:Nope': ..."."""
    from lanekeep.control.registry import check_controller
    from lanekeep.detectors.registry import check_detector

    source = scenario.source or scenario.name
    est = scenario.estimation
    checks = [*((f"estimation.front_detectors[{i}]", name, check_detector)
                for i, name in enumerate(est.front_detectors)),
              ("estimation.reference_detector", est.reference_detector, check_detector),
              ("control.controller", scenario.control.controller, check_controller)]
    for key, name, check in checks:
        try:
            check(name)
        except ConfigError as err:
            raise ScenarioError(source, key, err.message) from None


def add_options(p: argparse.ArgumentParser) -> None:
    """The three options, on `run` and on `bench` (where they apply to every scenario)."""
    names = "a built-in name, an entry point's or an import path package.module:Class"
    p.add_argument("--front-detectors", metavar="NAME[,NAME...]", default=None,
                   help=f"the front models instead of the scenario's ({names})")
    p.add_argument("--reference-detector", metavar="NAME", default=None,
                   help=f"the MMAE's reference detector instead of the scenario's ({names})")
    p.add_argument("--controller", metavar="NAME", default=None,
                   help=f"the controller instead of the scenario's [control] one: pid, stanley "
                        f"or {names}")
