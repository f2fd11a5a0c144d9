"""The scenario-format reference (docs/scenario_format.md), generated from the dataclasses.

Every key is documented at its field (lanekeep/core/setting.py `setting`: what it means, its
unit, its allowed values, and the bounds and choices the loader enforces), so the reference
cannot drift from the schema: types, defaults and the table layout come from
lanekeep/scenario/schema.py's dataclasses (and what they nest), the words from their fields'
metadata. tests/scenario/test_scenario_reference.py fails on a field without a description
(naming its dotted key) and on a committed file that differs from the generated one.

    python -m lanekeep.scenario.reference -o docs/scenario_format.md
"""

from __future__ import annotations

import argparse
import dataclasses
import types
import typing
from collections.abc import Iterator
from pathlib import Path

from lanekeep.core.setting import ALLOWED, DOC, unit_of
from lanekeep.scenario.schema import Scenario

UNDOCUMENTED = "(undocumented)"

CONVENTIONS = """\
## Conventions

- **Road coordinates** (Frenet): `s` is the arc length along the road's centre line from its
  start, in metres; `r` is the lateral distance from it, **+ = left**.
- **Curvature**: **+ = turning left** (anticlockwise seen from above), **- = turning right**;
  radius = 1 / |curvature|.
- **Lanes and boundaries count from the right**: `road.ego_lane = 0` is the **rightmost** lane;
  boundary 0 is the right edge line, boundary `n_lanes` the left one, and `[[road.markings]]`
  lists them rightmost first. The car drives towards increasing `s`; another vehicle with a
  negative speed drives towards decreasing `s` (oncoming).
- **Angles** are in degrees in the file; headings and yaw **+ = anticlockwise** (towards the
  left); camera pitch + = up.
- **Offsets** (`start.offset_m`, vehicles' `offset_m`, and the estimators' offsets): **+ =
  left** of the lane centre.
- Vehicle frame (detectors, estimators): x forward, y left, origin on the ground under the
  middle of the wheelbase.
- Reading is strict: an unknown key, a wrong type or a value outside its allowed range is an
  error naming the dotted key and the file. Integers are accepted where numbers are expected;
  booleans are never numbers. "not set" defaults are absent from the file (TOML has no null).
"""


def _type_name(tp) -> str:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return " or ".join(_type_name(a) for a in inner) + " (optional)"
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"array of {_type_name(args[0])}s"
        return f"array of {len(args)} {_type_name(args[0])}s"
    if dataclasses.is_dataclass(tp):
        return "table"
    return {str: "string", int: "integer", float: "number", bool: "boolean"}[tp]


def _value(value) -> str:
    if value is None:
        return "not set"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return str(value)


def _nested(tp) -> tuple[type | None, bool]:
    """(dataclass, is an array of tables) of a field type, or (None, False)."""
    if dataclasses.is_dataclass(tp):
        return tp, False
    args = typing.get_args(tp)
    if typing.get_origin(tp) is tuple and args and dataclasses.is_dataclass(args[0]):
        return args[0], True
    return None, False


def walk(cls: type = Scenario, prefix: str = "") -> Iterator[tuple[str, dataclasses.Field, object]]:
    """(dotted key, field, type) of every key a scenario file may hold, tables included,
    depth first in declaration order."""
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if not f.metadata.get("toml", True):
            continue
        path, tp = prefix + f.name, hints[f.name]
        yield path, f, tp
        inner, many = _nested(tp)
        if inner is not None:
            yield from walk(inner, path + ("[]." if many else "."))


def missing_descriptions(cls: type = Scenario) -> list[str]:
    """Dotted keys of `cls` whose field has no description (nested tables' too)."""
    return [path for path, f, _ in walk(cls) if not f.metadata.get(DOC)]


def _default(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        return _value(f.default)
    if f.default_factory is not dataclasses.MISSING:
        return _value(f.default_factory())
    return "required"


def _words(f: dataclasses.Field) -> tuple[str, str]:
    """(what the key means, its allowed values) from the field's metadata."""
    return f.metadata.get(DOC) or UNDOCUMENTED, f.metadata.get(ALLOWED, "any")


def _row(f: dataclasses.Field, tp) -> str:
    text, allowed = _words(f)
    cells = [f"`{f.name}`", _type_name(tp), unit_of(f), _default(f), allowed, text]
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


def _section(title: str, note: str, rows: list[str]) -> list[str]:
    head = ["| key | type | unit | default | allowed | meaning |", "|---|---|---|---|---|---|"]
    return ["", f"## {title}", "", *([note, ""] if note else []), *head, *rows]


def render(cls: type = Scenario) -> str:
    """The whole reference as Markdown: the top-level keys, then one section per table."""
    sections: dict[str, tuple[str, str, list[str]]] = {"": ("Top level", "", [])}
    for path, f, tp in walk(cls):
        inner, many = _nested(tp)
        if inner is not None:
            name = path.replace("[]", "")
            text, allowed = _words(f)
            note = f"{text} How many: {allowed}." if many else text
            sections[path] = (f"[[{name}]]" if many else f"[{name}]", note, [])
            continue
        parent = path.rsplit(".", 1)[0].removesuffix("[]") if "." in path else ""
        sections[parent][2].append(_row(f, tp))
    lines = ["# Scenario file format", "",
             "<!-- Generated by `python -m lanekeep.scenario.reference -o "
             "docs/scenario_format.md` from lanekeep/scenario/schema.py; edit the descriptions at "
             "the dataclass fields (`setting(...)`), not this file. -->", "",
             "A scenario is a TOML file (the shipped ones: `lanekeep/scenario/shipped/*.toml`; "
             "`lanekeep scenarios` lists them). Every key is optional unless its default says "
             "*required*.", "", CONVENTIONS.rstrip()]
    for title, note, rows in sections.values():
        lines += _section(title, note, rows)
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m lanekeep.scenario.reference",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, help="write here (default: stdout)")
    args = parser.parse_args(argv)
    text = render()
    if args.output is None:
        print(text, end="")
    else:
        args.output.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
