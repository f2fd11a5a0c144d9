"""Where `run` and `bench` write: `--json` (a file, or `-` for stdout), `--junit`, `--plots`,
`--record` / `--record-dir`.

One rule for all of them (docs/reports.md): a missing folder is created (by the writer, once
there is something to write); a path that could not be created or written is one error line,
exit 2, before anything runs, so that a long episode never ends in a write error. Each file
written is named on stderr ("wrote PATH"), as `--plots` and `--record` always did. With
`--json -` the JSON document is all that stdout holds (`lanekeep run X --json - | jq .steps`):
the tables and every other line go to stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, TextIO

from lanekeep.core.config_io import ConfigError
from lanekeep.core.files import folder_problem

STDOUT = "-"
EXIT_BAD_INPUT = 2

# (option, attribute, whether it names a folder rather than a file)
OUTPUT_OPTIONS = (("--json", "json", False), ("--junit", "junit", False),
                  ("--plots", "plots", True), ("--record", "record", False),
                  ("--record-dir", "record_dir", True),
                  ("--write-baseline", "write_baseline", False))


def error_line(command: str | None, message: object, one_line: bool = True) -> int:
    """Print the one error line of a refused command, "lanekeep CMD: error: MESSAGE" on
    stderr (whatever line breaks the message holds when `one_line`); returns exit code 2."""
    text = " ".join(str(message).split()) if one_line else str(message)
    print(f"lanekeep{f' {command}' if command else ''}: error: {text}", file=sys.stderr)
    return EXIT_BAD_INPUT


def human_stream(args: argparse.Namespace) -> TextIO:
    """Where tables and verdicts go: stdout, unless stdout carries the JSON (`--json -`)."""
    return sys.stderr if getattr(args, "json", None) == STDOUT else sys.stdout


def check_outputs(args: argparse.Namespace) -> None:
    """ConfigError naming the option for an output asked for whose folder could not be
    created or written (or `-` where only --json takes it); nothing is created here."""
    for option, attr, is_folder in OUTPUT_OPTIONS:
        path = getattr(args, attr, None)
        if path is None or (attr == "json" and path == STDOUT):
            continue
        if path == STDOUT:
            raise ConfigError("", option, "'-' (stdout) is for --json only; name a file")
        target = Path(path)
        if not is_folder and target.is_dir():
            raise ConfigError("", option, f"{path}: is a folder; name a file")
        problem = folder_problem(target if is_folder else target.parent)
        if problem:
            raise ConfigError("", option, f"{path}: {problem}")


def write_json_output(path: str, document: Any) -> None:
    """`document` as strict JSON to `path` (`-`: stdout), naming a file written on stderr."""
    from lanekeep.report.json_io import dumps, write_json

    if path == STDOUT:
        sys.stdout.write(dumps(document))
        sys.stdout.flush()
        return
    print(f"wrote {write_json(path, document)}", file=sys.stderr)


def write_junit_output(path: str, reports: dict, wall_s: float) -> None:
    """The JUnit XML of a bench to `path`, named on stderr."""
    from lanekeep.report.junit import write_junit

    write_junit(path, reports, wall_s)
    print(f"wrote {path}", file=sys.stderr)
