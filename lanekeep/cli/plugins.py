"""`run` and `bench` options that change the scenario for an episode without editing a file:
`--front-detectors`, `--reference-detector`, `--controller` swap its detectors and controller
(each a built-in name, an entry point's name or an import path `package.module:Class`,
lanekeep/core/plugins.py), so a user's own detector or controller runs on the shipped scenarios;
`--set KEY=VALUE` (repeatable) sets any other scenario key, so that two methods can be compared
on the same scenarios (`--set estimation.mmae_prior=uniform`).
"""

from __future__ import annotations

import argparse

from lanekeep.core.config_io import ConfigError
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.scenario.keys import parse_setting


def overrides_from_args(args: argparse.Namespace) -> PluginOverrides:
    """The options' choices, each name imported and each `--set` key checked: a bad or empty
    name, or a setting that is not KEY=VALUE or names no scenario key, is a ConfigError naming
    the option (a value is checked when a scenario is loaded, PluginOverrides.apply)."""
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
    settings = []
    for text in getattr(args, "settings", None) or ():
        try:
            settings.append(parse_setting(text))
        except ValueError as err:
            raise ConfigError("", "--set", str(err)) from None
    overrides = PluginOverrides(names, getattr(args, "reference_detector", None),
                                getattr(args, "controller", None), tuple(settings),
                                getattr(args, "detectors_config", None))
    overrides.check()
    return overrides


def add_options(p: argparse.ArgumentParser) -> None:
    """The options, on `run` and on `bench` (where they apply to every scenario)."""
    names = "a built-in name, an entry point's or an import path package.module:Class"
    p.add_argument("--front-detectors", metavar="NAME[,NAME...]", default=None,
                   help=f"the front models instead of the scenario's ({names})")
    p.add_argument("--reference-detector", metavar="NAME", default=None,
                   help=f"the MMAE's reference detector instead of the scenario's ({names})")
    p.add_argument("--controller", metavar="NAME", default=None,
                   help=f"the controller instead of the scenario's [control] one: pid, stanley "
                        f"or {names}")
    p.add_argument("--detectors-config", metavar="FILE", default=None,
                   help="a detectors TOML file (the keys of detectors/detectors.toml, e.g. "
                        "[hough] binarisation = \"ridge\") whose settings every scenario's "
                        "detectors run with, as if it were the scenario's [detectors] table "
                        "(applied before --set; recorded in bench --json under overrides)")
    p.add_argument("--set", dest="settings", action="append", metavar="KEY=VALUE", default=None,
                   help="set a scenario key for the episode, a dotted key as in "
                        "docs/scenario_format.md (road.segments[1].curvature_1pm) and a TOML "
                        "value (0.3, true, [\"hough\", \"lanenet\"]; a bare word is a "
                        "string); repeatable, applied in order after the options above, e.g. "
                        "--set estimation.mmae_prior=uniform")
