"""The one validation path of a scenario: what building its episode would reject, checked in
milliseconds before anything runs or any file is written. `check_scenario` is what `lanekeep
run`, `bench`, `perf`, a sweep's and a falsification's every parameter value
(lanekeep/sweep/spec.py `check_world`) and each sweep cell call; it adds to the checks of
reading the file (each field's range, lanekeep/scenario/*.py) the world's cross-field
checks (lanekeep/world/build.py `check_buildable`), the detector and controller names and a
`seconds` of at least one step. `check_weights_option` adds the weights files the learned
detectors load."""

from __future__ import annotations

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.schema import Scenario, ScenarioError


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


def check_scenario(scenario: Scenario, seconds: float | None = None) -> None:
    """Everything about a scenario that building its episode would reject, checked in 30-160 ms
    so that a bad scenario fails before anything runs or any file is written (`lanekeep
    bench` checks every scenario before a worker starts): the world's cross-field checks
    (lanekeep.world.build.check_buildable), the detector and controller names (imported), and
    that `seconds` makes at least one control step.

    Raises:
      ScenarioError: naming the scenario's file and key.
      ConfigError: `seconds` makes no control step (key "--seconds").
    """
    from lanekeep.world.build import check_buildable

    check_plugins(scenario)  # detector and controller names, import paths, entry points
    check_buildable(scenario)
    if seconds is not None and round(seconds / scenario.control_period_s) < 1:
        raise ConfigError("", "--seconds", f"{seconds:g} s is less than one control step "
                                           f"({scenario.control_period_s:g} s)")


def check_weights_option(scenarios: list[Scenario], weights: str | None) -> list[str]:
    """Load the weights file each learned detector of `scenarios` would use (`weights`, else
    its shipped one); a `weights` file is checked even if no scenario uses such a detector.
    Unknown detector names are left to `check_scenario`. Returns the files checked.

    Raises:
      ValueError: the first bad file's error, "FILE: why" (detectors.lanenet.WeightsError).
    """
    from lanekeep.detectors.registry import check_detectors_weights, known_detectors

    checked: list[str] = []
    for sc in scenarios:  # each with its own detectors settings (a `[lanenet] weights` table)
        names = [name for name in (*sc.estimation.front_detectors,
                                   sc.estimation.reference_detector)
                 if name in known_detectors()]
        checked += check_detectors_weights(names, sc.detectors, weights)
    if not scenarios and weights is not None:
        checked += check_detectors_weights([], None, weights)
    return list(dict.fromkeys(checked))
