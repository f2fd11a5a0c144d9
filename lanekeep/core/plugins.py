"""Plugins by name: a built-in name, an installed distribution's entry point, or an import path.

Wherever lanekeep accepts a detector or controller name it accepts, in this order:

* a built-in name ("hough", "pid"), from the kind's registry;
* a name an installed distribution registers in the entry-point group `lanekeep.detectors`
  or `lanekeep.control.registry`, e.g. in its pyproject.toml:

      [project.entry-points."lanekeep.detectors"]
      my_detector = "my_package.lanes:MyDetector"

* an import path `package.module:Attribute` (a module on sys.path / PYTHONPATH).

So a researcher tests their own detector or controller without editing this package. The
object found must be callable (a class or a factory function); what it is called with is the
kind's contract (lanekeep.detectors.registry, lanekeep.control.registry). Anything that cannot be
found is one `ConfigError` naming the name and why, which the CLI prints as one line, exit 2.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from importlib import metadata

from lanekeep.core.config_io import ConfigError

# "pkg.mod:Attr" or "pkg.mod:Outer.Inner": Python identifiers around exactly one colon.
_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
IMPORT_PATH = re.compile(rf"{_IDENT}(\.{_IDENT})*:{_IDENT}(\.{_IDENT})*")


@dataclass(frozen=True)
class PluginKind:
    """One kind of plugin: its entry-point group and the words its errors use."""

    group: str  # entry-point group, e.g. "lanekeep.detectors"
    noun: str  # "detector", "controller"


DETECTORS = PluginKind("lanekeep.detectors", "detector")
CONTROLLERS = PluginKind("lanekeep.control.registry", "controller")


def is_import_path(name: str) -> bool:
    """Whether `name` is meant as `package.module:Attribute` (it holds a colon)."""
    return ":" in name


def entry_point_names(kind: PluginKind) -> list[str]:
    """Names the installed distributions register in the kind's entry-point group."""
    return sorted({ep.name for ep in metadata.entry_points(group=kind.group)})


def _entry_point(kind: PluginKind, name: str) -> metadata.EntryPoint | None:
    found = metadata.entry_points(group=kind.group).select(name=name)
    return next(iter(found), None)


def load_import_path(path: str, kind: PluginKind, key: str = "") -> Callable:
    """The callable `path` ("package.module:Attribute") names.

    Raises:
      ConfigError: the path is malformed, its module cannot be imported, it has no such
        attribute, or the attribute is not callable; the message names `path`.
    """
    def fail(why: str) -> ConfigError:
        return ConfigError("", key, f"{kind.noun} {path!r}: {why}")

    if not IMPORT_PATH.fullmatch(path):
        raise fail("not an import path of the form package.module:Attribute")
    module_name, attribute = path.split(":")
    try:
        obj = importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        missing = f"no module named {err.name!r}" if err.name else str(err)
        raise fail(f"cannot import {module_name!r} ({missing})") from None
    except Exception as err:  # the plugin's own module failed while it was imported
        raise fail(f"importing {module_name!r} failed: {type(err).__name__}: {err}") from None
    for part in attribute.split("."):
        if not hasattr(obj, part):
            raise fail(f"module {module_name!r} has no attribute {attribute!r}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise fail(f"{attribute!r} is of type {type(obj).__name__!r}, not a class or function")
    return obj


def build(name: str, kind: PluginKind, factory: Callable, *args, **kwargs):
    """`factory(*args, **kwargs)` for a plugin's factory: whatever it raises becomes one
    ConfigError naming the plugin and the error (`--debug` shows the plugin's traceback as
    the error's cause), so that a user's bug reads as such rather than as lanekeep's."""
    try:
        return factory(*args, **kwargs)
    except Exception as err:
        raise ConfigError("", "", f"{kind.noun} {name!r} failed to build: "
                                  f"{type(err).__name__}: {err}") from err


def resolve(name: str, kind: PluginKind, builtin: dict[str, Callable], key: str = "",
            known: Callable[[], list[str]] | None = None) -> Callable:
    """The factory `name` stands for: built-in, entry point, or import path (module docstring).

    `known()` lists the names an "unknown" error offers (default: the built-ins and the entry
    points); it is called only then. Raises ConfigError naming `name` (and `key`, where a
    file or option gave it).
    """
    if name in builtin:
        return builtin[name]
    if is_import_path(name):
        return load_import_path(name, kind, key)
    point = _entry_point(kind, name)
    if point is not None:
        try:
            obj = point.load()
        except Exception as err:
            raise ConfigError("", key, f"{kind.noun} {name!r} (entry point {point.value!r} of "
                                       f"group {kind.group!r}): {type(err).__name__}: {err}"
                              ) from None
        if not callable(obj):
            raise ConfigError("", key, f"{kind.noun} {name!r} (entry point {point.value!r}): "
                                       f"of type {type(obj).__name__!r}, not a class or "
                                       f"function")
        return obj
    offered = known() if known is not None else sorted({*builtin, *entry_point_names(kind)})
    raise ConfigError("", key, f"unknown {kind.noun} {name!r} (known: {', '.join(offered)}; "
                               f"or an import path package.module:Class)")



# A plug-in's own `name` that can label it: no colon (an import path's mark), no spaces.
_LABEL = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def plugin_labels(names: Sequence[str], kind: PluginKind,
                  reserved: Collection[str] = ()) -> list[str]:
    """How reports, tables and recordings call the plug-ins `names`: a built-in's or an entry
    point's name as given; one given by import path by the class's own `name` attribute (its
    contract, docs/plugins.md), as its author calls it, unless that is no plain word, is
    `reserved` (a built-in's name, a report's own column), names another of `names` or
    labels one already, or the path does not import; then by its import path. A function of
    the names alone, so that whoever reads a scenario finds the episode's labels."""
    labels: list[str] = []
    for name in names:
        own = None
        if is_import_path(name):
            try:
                own = getattr(load_import_path(name, kind), "name", None)
            except ConfigError:
                own = None
        ok = (isinstance(own, str) and _LABEL.fullmatch(own) is not None
              and own not in {*reserved, *names, *labels})
        labels.append(own if ok else name)
    return labels
