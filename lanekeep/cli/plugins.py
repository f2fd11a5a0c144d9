"""`run` and `bench` options that swap the scenario's detectors and controller for an episode:
`--front-detectors`, `--reference-detector`, `--controller`. Each takes a built-in name, an
entry point's name or an import path `package.module:Class` (lanekeep/core/plugins.py), so a user's
own detector or controller runs on the shipped scenarios without editing a file.
"""

from __future__ import annotations

import argparse

from lanekeep.core.config_io import ConfigError
from lanekeep.loop.overrides import PluginOverrides


def overrides_from_args(args: argparse.Namespace) -> PluginOverrides:
    """The options' choices, each name imported: a bad or empty name is a ConfigError
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
    overrides = PluginOverrides(names, getattr(args, "reference_detector", None),
                    getattr(args, "controller", None))
    overrides.check()
    return overrides


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
