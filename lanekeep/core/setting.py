"""A setting's one definition: its default, meaning, unit and allowed values at its field.

    offset_lookahead_m: float = setting(4.0, "Where the front offsets are compared.",
                                        bounds=(0.0, 40.0))
    output: str = setting("precision", "How the models' lanes become one.",
                          choices=("select", "fused", "precision"))

The field's metadata is what the scenario reference (lanekeep/scenario/reference.py) writes
into docs/scenario_format.md, and `check_settings` (called from the dataclass's
``__post_init__``) enforces its `bounds` and `choices`, so the values a reader sees are the
values the loader accepts. Rules they cannot say ("0 or 10..100", across fields) stay in
``__post_init__`` and are described in `allowed`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from lanekeep.core.config_io import InvalidValue

DOC, UNIT, ALLOWED, BOUNDS, CHOICES = "doc", "unit", "allowed", "bounds", "choices"


def setting(default: Any = dataclasses.MISSING, doc: str = "", *, unit: str = "",
            allowed: str = "", bounds: tuple[float, float] | None = None,
            choices: tuple[str, ...] | None = None, factory: Any = dataclasses.MISSING,
            **metadata: Any) -> Any:
    """A dataclass field with its documentation: `doc` what it means (with its sign
    convention), `unit` where the name's suffix does not say it, `bounds` (inclusive) or
    `choices` the values `check_settings` accepts, `allowed` the values a file may give in
    words (from `bounds` or `choices` when not given), `factory` a default_factory; further
    `metadata` (e.g. ``toml=False``) is kept."""
    meta = {DOC: doc, **metadata}
    if unit:
        meta[UNIT] = unit
    if bounds is not None:
        meta[BOUNDS] = bounds
    if choices is not None:
        meta[CHOICES] = tuple(choices)
    text = allowed or (bounds_text(bounds) if bounds is not None else "") or (
        choices_text(choices) if choices is not None else "")
    if text:
        meta[ALLOWED] = text
    if factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def same_as(cls: type, name: str) -> Any:
    """A field defined by dataclass `cls`'s field `name` (its default and metadata), for a
    key two dataclasses hold: the scenario's flat table and the type that uses it."""
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    return dataclasses.field(default=f.default, default_factory=f.default_factory,
                             metadata=f.metadata)


# Units from a key's suffix (the project names units in keys), longest suffix first.
SUFFIX_UNITS = (("_dps_rthz", "deg/s/sqrt(Hz)"), ("_dps_rts", "deg/s/sqrt(s)"),
                ("_mps2_rthz", "m/s^2/sqrt(Hz)"), ("_per_100m", "per 100 m"),
                ("_1pm", "1/m"), ("_mps", "m/s"), ("_dps", "deg/s"), ("_deg", "deg"),
                ("_dn", "DN"), ("_px", "px"), ("_m", "m"), ("_s", "s"))


def unit_of(f: dataclasses.Field) -> str:
    """A field's unit: its metadata's, else its name's suffix's ("" for none)."""
    if UNIT in f.metadata:
        return f.metadata[UNIT]
    return next((unit for suffix, unit in SUFFIX_UNITS if f.name.endswith(suffix)), "")


def bounds_text(bounds: tuple[float, float]) -> str:
    low, high = bounds
    return f"{low:g}..{high:g}"


def choices_text(choices: tuple[str, ...]) -> str:
    return ", ".join(f'"{c}"' for c in choices)


def check_settings(obj: Any) -> None:
    """InvalidValue naming the first field of `obj` outside its `bounds` or `choices` (None
    is not checked: an optional key left unset)."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        choices = f.metadata.get(CHOICES)
        if choices is not None and value is not None and value not in choices:
            raise InvalidValue(f.name, f"must be one of {choices}, got {value!r}")
        bounds = f.metadata.get(BOUNDS)
        if bounds is None or value is None:
            continue
        low, high = bounds
        if not (math.isfinite(value) and low <= value <= high):
            unit = unit_of(f)
            raise InvalidValue(f.name, f"must be in [{low:g}, {high:g}]{' ' + unit if unit else ''}"
                                       f", got {value}")
