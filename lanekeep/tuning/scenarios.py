"""Which scenarios a tuning tool may measure on: the tuning scenarios,
lanekeep/tuning/scenario_files/*.toml (package data), by default; a shipped scenario (scored by
`lanekeep bench` at its file's seed) only when asked.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from lanekeep.scenario.schema import ScenarioError, load_scenario, shipped_scenarios

TUNING_SEEDS_START = 1000
"""The first tuning seed: seeds from here on are the tuning tools' (`lanekeep bench --help`), so a
limit or a setting fitted on them is judged on seeds it never saw."""
SCORED_SEEDS = range(0, TUNING_SEEDS_START)
"""The seeds `lanekeep bench --seeds` scores: no tuning may look at an episode on one of them."""


class TuningInputError(Exception):
    """A user error of a tuning tool: its message is one line, the tool exits 2."""


def tuning_dir() -> Path:
    """The folder of the tuning scenarios, lanekeep.tuning.scenario_files, wherever the package
    is installed (a folder on disk: the tools hand its files to `load_scenario` by path)."""
    return Path(str(resources.files("lanekeep.tuning.scenario_files")))


def tuning_scenarios(folder: Path | None = None) -> list[Path]:
    """The tuning scenario files (`folder`'s *.toml, by default `tuning_dir()`'s), sorted."""
    return sorted(Path(tuning_dir() if folder is None else folder).glob("*.toml"))


def select_scenarios(scenarios: Sequence[str], folder: Path | None = None,
                     allow_scored: bool = False) -> list[str]:
    """The scenario arguments to measure on: `scenarios` as given, or every tuning scenario
    in `folder` (by default `tuning_dir()`).

    Raises TuningInputError when there are no tuning scenarios, a scenario does not load, or
    one is shipped (by name or file) and `allow_scored` is false.
    """
    folder = tuning_dir() if folder is None else folder
    selected = list(scenarios) or [str(path) for path in tuning_scenarios(folder)]
    if not selected:
        raise TuningInputError(f"no tuning scenarios in {folder}")
    shipped = set(shipped_scenarios())
    for arg in selected:
        try:
            name = load_scenario(arg).name
        except ScenarioError as err:
            raise TuningInputError(str(err)) from None
        if (name in shipped or Path(arg).stem in shipped) and not allow_scored:
            raise TuningInputError(f"{arg} is a shipped scenario, scored by `lanekeep bench`: "
                                   f"tune on lanekeep/tuning/scenario_files/ "
                                   f"(or pass --allow-scored)")
    return selected


def shown(arg: str) -> str:
    """A scenario argument as given, or a tuning file relative to the working directory."""
    try:
        return str(Path(arg).resolve().relative_to(Path.cwd()))
    except ValueError:
        return arg


def own_seed(scenario_arg: str) -> int | None:
    """The seed a scenario's file gives it (the one the bench scores); None if it will not
    load (`select_scenarios` then says why)."""
    try:
        return load_scenario(scenario_arg).seed
    except ScenarioError:
        return None


def add_scenario_arguments(parser: argparse.ArgumentParser,
                           default: str = "every tuning scenario, lanekeep/tuning/scenario_files/"
                           ) -> None:
    """The tuning tools' shared arguments: scenario names or files (`default` says what none
    means) and --allow-scored, which `select_scenarios` needs for a shipped scenario."""
    parser.add_argument("scenarios", nargs="*",
                        help=f"scenario names or files (default: {default})")
    parser.add_argument("--allow-scored", action="store_true",
                        help="allow shipped scenarios, which `lanekeep bench` scores")
