"""The command line's changes to a scenario for an episode (options of `run` and `bench`).

`--front-detectors`, `--reference-detector` and `--controller` swap its detectors and
controller: a built-in name, an entry point's name or an import path `package.module:Class`
(lanekeep/core/plugins.py), so a user's own detector or controller runs on the shipped
scenarios without editing a file. `--set KEY=VALUE` changes any other scenario key the same way
(`estimation.mmae_prior=uniform`): how two methods are compared on the same scenarios.
`--detectors-config FILE` gives every scenario a detectors file's settings as its
`[detectors]` table (a scenario file's own table is the reproducible way to keep them).
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
from dataclasses import dataclass
from typing import Any

from lanekeep.core.config_io import ConfigError
from lanekeep.detectors.config import DetectorsConfig, load_config
from lanekeep.scenario.keys import check_key, with_settings
from lanekeep.scenario.schema import Scenario, ScenarioError


@dataclass(frozen=True)
class PluginOverrides:
    """The command line's changes to a scenario; None (or no settings) keeps the file's."""

    front_detectors: tuple[str, ...] | None = None
    reference_detector: str | None = None
    controller: str | None = None
    # (dotted key, TOML value) of each `--set`, in the command line's order, applied last
    settings: tuple[tuple[str, Any], ...] = ()
    # a detectors file (`--detectors-config`) that becomes every scenario's `[detectors]`
    detectors_config: str | None = None

    def check(self) -> None:
        """Import each name given and check each setting's key names a scenario key
        (ConfigError naming the option), before any scenario is loaded; a setting's value and
        array indices are checked against each scenario by `apply`."""
        from lanekeep.control.registry import check_controller
        from lanekeep.detectors.registry import check_detector

        for name in self.front_detectors or ():
            check_detector(name, "--front-detectors")
        if self.reference_detector is not None:
            check_detector(self.reference_detector, "--reference-detector")
        if self.controller is not None:
            check_controller(self.controller, "--controller")
        if self.detectors_config is not None:
            self.detectors()
        for key, _ in self.settings:
            try:
                check_key(key, None, seed_rule="use --seed")
            except ValueError as err:
                raise ConfigError("", "--set", f"{key}: {err}") from None

    def detectors(self) -> DetectorsConfig | None:
        """The detectors file's settings (None: none given); a file that cannot be read or
        holds a bad key is a ConfigError naming the option and the file."""
        if self.detectors_config is None:
            return None
        try:
            return load_config(self.detectors_config)
        except OSError as err:
            raise ConfigError("", "--detectors-config",
                              f"{self.detectors_config}: {err.strerror or err}") from None
        except tomllib.TOMLDecodeError as err:
            raise ConfigError("", "--detectors-config",
                              f"{self.detectors_config}: invalid TOML: {err}") from None
        except ConfigError as err:
            raise ConfigError("", "--detectors-config", str(err)) from None

    def apply(self, scenario: Scenario) -> Scenario:
        """`scenario` with these changes in place of its own: the detectors and controller,
        then the settings. A setting the scenario cannot take is the ScenarioError its file
        would give, naming the key, with the settings that caused it (one may break a rule
        across keys, e.g. `road.n_lanes=1` with the file's `road.ego_lane = 1`)."""
        est = scenario.estimation
        if self.front_detectors is not None:
            est = dataclasses.replace(est, front_detectors=self.front_detectors)
        if self.reference_detector is not None:
            est = dataclasses.replace(est, reference_detector=self.reference_detector)
        control = scenario.control
        if self.controller is not None:
            control = dataclasses.replace(control, controller=self.controller)
        scenario = dataclasses.replace(scenario, estimation=est, control=control)
        if self.detectors_config is not None:
            scenario = dataclasses.replace(scenario, detectors=self.detectors())
        try:
            return with_settings(scenario, self.settings)
        except ScenarioError as err:
            shown = " ".join(f"--set {key}={_toml(value)}" for key, value in self.settings)
            raise ScenarioError(err.source, err.key, f"{err.message} (after {shown})") from None


def _toml(value: Any) -> str:
    """A value as it could be typed after `--set KEY=` (JSON's scalars and arrays are TOML's)."""
    return json.dumps(value, ensure_ascii=False, default=str)
