"""Detectors by name: the episode and the CLI build them here.

    make_detector("sliding_window", camera)            # tuned config from detectors.toml
    make_detector("hough", camera, load_config(path))  # another config file

A new detector is one module that defines its class (and, if it has settings, a frozen
dataclass of them) and registers both:

    register_detector("my_detector", MyDetector, settings=MySettings)

Its settings then come from a `[my_detector]` table of the detectors TOML file, checked as
strictly as the rest (an unknown key names itself), and reach the detector as `settings=`.

A detector whose module is costly to import (LaneNet imports torch, ~1 s) is registered by
module and attribute names instead, and imported the first time it is made:

    register_lazy_detector("lanenet", "lanekeep.detectors.lanenet", "LaneNetDetector",
                           "LaneNetSettings")

A learned detector takes `weights=` (a file); `make_detector(..., weights=FILE)` passes it on to
those that accept it, and `detector_weights(FILE)` scopes the same override around code that
builds its detectors itself (an `Episode`). Within the scope a file goes only to the detectors of
its format (a class's `weights_format`, e.g. LaneNet's "lanekeep-lanenet/1"): a LaneNet file
given to a loop with the row-anchor observer as its reference reaches LaneNet, and the observer
keeps its own.

A detector outside this package needs no registration: every name taken here may also be an
import path `package.module:Class`, or a name an installed distribution registers in the
entry-point group `lanekeep.detectors` (lanekeep/core/plugins.py). Its constructor contract is the
built-ins' one:

    Class(camera, config=DetectorsConfig | None, distortion=np.ndarray | None
          [, weights=str | None])  # weights only if it takes them (learned detectors)

where `camera` is the CameraModel it looks through (intrinsics, mounting, its name "front" or
"rear"), `config` the shared detectors TOML and `distortion` the lens's OpenCV coefficients.
The instance must meet `Detector` (detectors/base.py): `name`, `x_ref`, `window`,
`detect(frame)` and `reset()`; anything else is a ConfigError naming it.

A plug-in class that subclasses a registered detector is of that detector's family
(`builtin_family`): the loop gives it what it keys by that name (docs/plugins.md).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from importlib import resources

import numpy as np

from lanekeep.core import plugins
from lanekeep.core.config_io import ConfigError, from_dict
from lanekeep.detectors.base import Detector
from lanekeep.detectors.config import DetectorsConfig, load_config, register_table
from lanekeep.detectors.hough import HoughDetector
from lanekeep.detectors.sliding_window import SlidingWindowDetector
from lanekeep.geometry.camera_model import CameraModel

Factory = Callable[..., Detector]

DETECTORS: dict[str, Factory] = {
    "hough": HoughDetector,
    "sliding_window": SlidingWindowDetector,
}
SETTINGS: dict[str, type] = {}  # detector name -> its settings dataclass, if it has one


@dataclass(frozen=True)
class LazyDetector:
    """A detector class and its settings dataclass named by module and attribute: importing
    them is left to the first `make_detector`, so commands that never use it do not pay for
    its imports."""

    module: str
    factory: str
    settings: str | None = None

    def load(self) -> tuple[Factory, type | None]:
        mod = importlib.import_module(self.module)
        return getattr(mod, self.factory), (getattr(mod, self.settings) if self.settings
                                            else None)


LAZY: dict[str, LazyDetector] = {}
# A weights file for every detector made in this context that takes one (see detector_weights).
_WEIGHTS: ContextVar[str | None] = ContextVar("detector_weights", default=None)


def register_detector(name: str, factory: Factory, settings: type | None = None) -> None:
    """Make `factory(camera, config=..., distortion=...[, settings=...])` known as `name`."""
    if name in DETECTORS or name in LAZY:
        raise ValueError(f"a detector named {name!r} is already registered")
    DETECTORS[name] = factory
    if settings is not None:
        SETTINGS[name] = settings
        register_table(name)


def register_lazy_detector(name: str, module: str, factory: str,
                           settings: str | None = None) -> None:
    """`register_detector` for a detector imported on first use (see LazyDetector)."""
    if name in DETECTORS or name in LAZY:
        raise ValueError(f"a detector named {name!r} is already registered")
    LAZY[name] = LazyDetector(module, factory, settings)
    if settings is not None:
        register_table(name)


def _resolve(name: str, key: str = "") -> Factory:
    """The factory of `name`, importing a lazy detector's module (once) if needed; else an
    entry point's or an import path's (lanekeep/core/plugins.py).

    Raises:
      ConfigError: an unknown name or a bad import path, naming it (and `key`).
    """
    if name in LAZY and name not in DETECTORS:
        factory, settings = LAZY[name].load()
        DETECTORS[name] = factory
        if settings is not None:
            SETTINGS[name] = settings
    return plugins.resolve(name, plugins.DETECTORS, DETECTORS, key, known_detectors)


def check_detector(name: str, key: str = "") -> None:
    """Fail now, not mid-run, on a name that makes no detector (ConfigError naming it)."""
    _resolve(name, key)


def known_detectors() -> list[str]:
    """Built-in names and those installed distributions register as entry points."""
    return sorted(set(DETECTORS) | set(LAZY) | set(plugins.entry_point_names(plugins.DETECTORS)))


def _registered_classes() -> dict[tuple[str, str], str]:
    """(module, qualified name) of each registered detector class -> its registered name; a
    lazy one by the names it was registered with, so that nothing is imported to find it."""
    found = {(lazy.module, lazy.factory): name for name, lazy in LAZY.items()}
    found.update({(f.__module__, f.__qualname__): name for name, f in DETECTORS.items()
                  if inspect.isclass(f)})
    return found


def builtin_family(detector: object) -> str | None:
    """The registered name of the nearest registered class `detector` (a detector, its class,
    or a name `make_detector` takes) is, or inherits from: "lanenet" for a plug-in
    `class Sham(LaneNetDetector)`, None for one that subclasses no registered detector.

    Why: the loop keys what it measured per detector by name (a tracker's noise, the MMAE's
    prior, paper mode's windows, a `[name]` settings table); a subclass that changes nothing
    but its `name` must run the loop its built-in runs, not a plug-in's pooled defaults. A
    plug-in that wraps a built-in instead of subclassing it says so with a class attribute
    `family = "lanenet"` (examples/sabotage.py)."""
    if isinstance(detector, str):
        detector = _resolve(detector)
    cls = detector if inspect.isclass(detector) else type(detector)
    declared = getattr(cls, "family", None)  # a wrapper that holds a built-in says which
    if isinstance(declared, str) and declared:
        return declared
    registered = _registered_classes()
    for ancestor in cls.__mro__:
        name = registered.get((ancestor.__module__, ancestor.__qualname__))
        if name is not None:
            return name
    return None


def front_labels(names: Sequence[str]) -> list[str]:
    """The labels reports, recordings and the agent faces give the front detectors `names`: a
    plug-in given by import path by its own `name` (lanekeep/core/plugins.py `plugin_labels`),
    never a built-in's name nor a report's own columns ("fused", "reference")."""
    return plugins.plugin_labels(names, plugins.DETECTORS,
                                 {*known_detectors(), "fused", "reference"})


def takes_weights(name: str) -> bool:
    """Whether detector `name` is built from a weights file (its factory takes `weights=`)."""
    return "weights" in inspect.signature(_resolve(name)).parameters


def _file_format(path: str) -> str | None:
    """The `format` a weights file declares, or None where it cannot be read as one (the
    detector that loads it then names the problem)."""
    try:
        import torch

        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception:  # noqa: BLE001 - unreadable for any reason: the loader says why
        return None
    return blob.get("format") if isinstance(blob, dict) else None


def weights_fit(name: str, path: str) -> bool:
    """Whether weights file `path` is of detector `name`'s format (its class's
    `weights_format`); True for a detector that declares none and for a file whose format
    cannot be read, so that the detector's own loader reports what is wrong with it."""
    wanted = getattr(_resolve(name), "weights_format", None)
    if wanted is None:
        return True
    found = _file_format(str(path))
    return found is None or found == wanted


def _scoped_weights(name: str) -> str | None:
    """The `detector_weights` scope's file if it is of `name`'s format, else None."""
    path = _WEIGHTS.get()
    return path if path is not None and weights_fit(name, path) else None


@contextmanager
def detector_weights(path: str | None) -> Iterator[None]:
    """Within this block, detectors that take weights are made from `path` (None: their own
    default). The episode builds its detectors itself; the CLI's `--weights` reaches them
    through this scope instead of through every constructor between them."""
    token = _WEIGHTS.set(path)
    try:
        yield
    finally:
        _WEIGHTS.reset(token)


def make_detector(
    name: str,
    camera: CameraModel,
    config: DetectorsConfig | None = None,
    distortion: np.ndarray | None = None,
    weights: str | None = None,
) -> Detector:
    """A detector `name` on `camera` (its ground window is picked by the camera's name:
    "front", "rear", anything else = a real dashcam). Unknown names, bad import paths and
    objects that are no Detector raise ConfigError (a ValueError).

    `weights` goes only to detectors that take one (and the `detector_weights` scope's file
    only to those of its format); a learned detector without either loads its own default
    file. A file that cannot be loaded raises the detector's error (a ValueError whose message
    starts with the path).
    """
    factory = _resolve(name)
    extra = {}
    if takes_weights(name):
        weights = weights if weights is not None else _scoped_weights(name)
        if weights is not None:
            extra["weights"] = weights
    if name not in DETECTORS:  # a plugin (import path, entry point): its errors name it
        extra.update(_inherited_settings(factory, config))
        detector = plugins.build(name, plugins.DETECTORS, factory, camera, config=config,
                                 distortion=distortion, **extra)
    elif name not in SETTINGS:
        detector = factory(camera, config=config, distortion=distortion, **extra)
    else:
        config = config or load_config()
        detector = factory(camera, config=config, distortion=distortion,
                           settings=detector_settings(name, config), **extra)
    if not isinstance(detector, Detector):  # a plugin's mistake, named before it runs
        missing = [a for a in ("name", "x_ref", "window", "detect", "reset")
                   if not hasattr(detector, a)]
        raise ConfigError("", "", f"detector {name!r} made a {type(detector).__name__}, not a "
                                  f"Detector (missing: {', '.join(missing)})")
    return detector


def _inherited_settings(factory: Factory, config: DetectorsConfig | None) -> dict:
    """`{"settings": ...}` from the `[family]` table for a plug-in that subclasses a registered
    detector with settings and keeps its constructor (so takes those settings); else {}."""
    family = builtin_family(factory) if inspect.isclass(factory) else None
    if family is None or factory.__init__ is not _resolve(family).__init__:
        return {}
    settings = detector_settings(family, config)
    return {} if settings is None else {"settings": settings}


def detector_settings(name: str, config: DetectorsConfig | None = None):
    """The settings dataclass of `name` from its `[name]` table (None if it has none)."""
    _resolve(name)
    if name not in SETTINGS:
        return None
    config = config or load_config()
    return from_dict(SETTINGS[name], config.tables.get(name, {}), path=name,
                     source="detectors config")


def check_weights(name: str, config: DetectorsConfig | None = None,
                  weights: str | None = None) -> str | None:
    """Load the weights file detector `name` would be made from (no camera, no frame needed),
    so that a command can reject a bad file before it runs anything or writes any output.

    A learned detector's module provides `load_weights(path)` and `DEFAULT_WEIGHTS` (its
    shipped file, inside the detectors package); the file is, as when it is made: `weights`,
    else the `detector_weights` scope's if it is of this detector's format, else its
    settings' `weights`, else the shipped one.
    Returns the file's path, or None for a detector without weights.
    Raises:
      ValueError: the detector's own error for that file (WeightsError: "PATH: why").
    """
    if not takes_weights(name):
        return None
    module = importlib.import_module(_resolve(name).__module__)
    if not hasattr(module, "load_weights"):  # a plugin that loads its weights its own way
        return None
    weights = weights if weights is not None else _scoped_weights(name)
    if weights is None:
        weights = (getattr(detector_settings(name, config), "weights", "")
                   or str(resources.files("lanekeep.detectors").joinpath(module.DEFAULT_WEIGHTS)))
    module.load_weights(weights)
    return str(weights)


def check_detectors_weights(names: list[str], config: DetectorsConfig | None = None,
                            weights: str | None = None) -> list[str]:
    """`check_weights` for each of `names` that takes weights: the files they would load.

    A `weights` file goes to those of `names` of its format (`weights_fit`); the others are
    checked with their own files. It must fit one of them, or, while none of `names` takes
    weights, some learned detector (LaneNet's or the row-anchor observer's), so that a wrong
    path on a command line is reported, not ignored.
    Raises:
      ValueError: the first bad file's error ("PATH: why").
    """
    learned = [n for n in dict.fromkeys(names) if takes_weights(n)]
    if learned and weights is not None:
        fitting = [n for n in learned if weights_fit(n, weights)]
        if not fitting:  # the first one's loader names what the file is not
            check_weights(learned[0], config, weights)
        return [path for n in learned
                if (path := check_weights(n, config, weights if n in fitting else None))]
    if not learned and weights is not None:
        errors = []
        for n in (n for n in known_detectors() if takes_weights(n)):
            try:
                path = check_weights(n, config, weights)
            except ValueError as exc:
                errors.append(exc)
                continue
            return [path] if path else []
        if errors:
            raise errors[0]
        return []
    return [path for n in learned if (path := check_weights(n, config, weights))]


# LaneNet (paper 000) imports torch: registered lazily so that classical-only commands start
# in ~0.2 s instead of ~1.2 s.
register_lazy_detector("lanenet", "lanekeep.detectors.lanenet", "LaneNetDetector",
                       "LaneNetSettings")
# The row-anchor network (#58): the rear reference that shares nothing learned with a front
# model; selectable by name, not the default.
register_lazy_detector("rowanchor", "lanekeep.detectors.rowanchor", "RowAnchorDetector",
                       "RowAnchorSettings")
