"""Strict conversion of parsed TOML tables into frozen dataclasses.

A scenario file is data typed by hand, so every mistake must be reported where it was made: an
unknown key, a wrong type or a bad value raises `ConfigError` whose message carries the dotted key
path (``road.segments[1].lenght_m``) and the file. Dataclasses validate their own values in
``__post_init__`` by raising `InvalidValue` with the field name; the loader prefixes the path.

Type rules: ints are accepted where floats are expected; bools are never numbers; arrays become
tuples; nested tables become nested dataclasses. Fields with ``metadata={"toml": False}`` are not
readable from the file (e.g. ``Scenario.source``).
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any, TypeVar

T = TypeVar("T")


class InvalidValue(ValueError):
    """A dataclass field holds a value outside its allowed range or set."""

    def __init__(self, key: str, message: str):
        super().__init__(f"{key}: {message}")
        self.key = key
        self.message = message


class ConfigError(ValueError):
    """A configuration table does not match its dataclass; the message names key and file."""

    def __init__(self, source: str, key: str, message: str):
        super().__init__(": ".join(part for part in (source, key, message) if part))
        self.source = source
        self.key = key
        self.message = message


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", None) or str(tp).replace("typing.", "")


def _convert(value: Any, tp: Any, path: str, source: str) -> Any:
    """Convert one TOML value to the annotated type `tp`, or raise ConfigError at `path`."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [arg for arg in args if arg is not type(None)]
        if len(inner) == 1:  # an optional value: its own error, at its own key
            return _convert(value, inner[0], path, source)
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _convert(value, arg, path, source)
            except ConfigError as err:
                errors.append(err.message)
        raise ConfigError(source, path, " / ".join(errors))
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise ConfigError(source, path, f"expected a table, got {type(value).__name__}")
        # A settings class with its own reading rules (defaults that depend on the table a
        # key sits in) reads its table itself.
        reader = getattr(tp, "from_table", None)
        if reader is not None:
            return reader(value, path=path, source=source)
        return from_dict(tp, value, path=path, source=source)
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            raise ConfigError(source, path, f"expected an array, got {type(value).__name__}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{path}[{i}]", source) for i, v in enumerate(value))
        if args and len(value) != len(args):
            raise ConfigError(source, path, f"expected {len(args)} values, got {len(value)}")
        return tuple(
            _convert(v, a, f"{path}[{i}]", source)
            for i, (v, a) in enumerate(zip(value, args, strict=True))
        )
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(source, path, f"expected a number, got {type(value).__name__}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, path, f"expected an integer, got {type(value).__name__}")
        return value
    if tp in (bool, str):
        if not isinstance(value, tp):
            raise ConfigError(
                source, path, f"expected {_type_name(tp)}, got {type(value).__name__}"
            )
        return value
    raise TypeError(f"config_io cannot convert to {tp!r} (at {path})")


def from_dict(cls: type[T], data: dict[str, Any], path: str = "", source: str = "") -> T:
    """Build dataclass `cls` from a parsed TOML table, strictly.

    Args:
      cls: a dataclass type; field annotations drive the conversion.
      data: the table.
      path: dotted key path of `data` in the file, for messages.
      source: the file name, for messages.

    Raises:
      ConfigError: unknown key, missing required key, wrong type, or invalid value.
    """
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.metadata.get("toml", True)}
    for key in data:
        if key not in fields:
            known = ", ".join(sorted(fields))
            raise ConfigError(source, _join(path, key), f"unknown key (known keys: {known})")
    kwargs = {}
    for name, field in fields.items():
        if name in data:
            kwargs[name] = _convert(data[name], hints[name], _join(path, name), source)
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            raise ConfigError(source, _join(path, name), "required key is missing")
    try:
        return cls(**kwargs)
    except InvalidValue as err:
        raise ConfigError(source, _join(path, err.key), err.message) from None
