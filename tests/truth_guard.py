"""The truth guard: proves at run time that perception, estimation and control run without the
truth, where the layer rule (tests/project/test_layers.py) cannot: plug-ins loaded by import
path.

An episode keeps the simulator's truth behind one gate (`episode.truth`,
lanekeep/scoring/gate.py) that only scoring, recording, the sensors and the renderer are handed.
`guard_truth(episode)` checks that, three ways, with no exemption for who is up the stack:

1. Reach, before and after the run: nothing the car side holds (the detectors, the estimator,
   the controller, the odometry, the roll filter: their attributes, containers, closures and
   class attributes, followed to the end) leads to a truth object (the episode, its gate, the
   world, the MuJoCo model and data, the car, the road and its segments, what the conditions
   laid, the scenario and its road and conditions, the renderer, the effects, the sensors).
2. Reads: while any car-side method runs (whoever called it, on whichever thread), every
   attribute read of any of those truth objects raises `TruthLeak`, the gate's included.
3. The loop's own reads go through the gate: `episode.world` and `episode.scenario` (the
   faces' and tools' doors to the truth) raise for the whole guarded run.

The episode's classes are put back when it closes. Test-only: the loop itself checks nothing.
"""

from __future__ import annotations

import functools
import gc
import threading
import types
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager

from lanekeep.loop.episode import Episode

MAX_REACH = 2_000_000  # objects one reach walk may visit before it gives up (and fails)


class TruthLeak(BaseException):  # noqa: N818 - the name says what it catches
    """Perception, estimation or control read (or holds) the simulator's truth.

    A BaseException so that no `except Exception` on the way (a failing detector counts as
    a miss in lanekeep/driver/detection.py) can swallow it."""


class _Phase:
    """Whether car-side code is running now (a count, across threads) and which."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.running: list[str] = []
        self.leaks: list[str] = []

    @contextmanager
    def car_side(self, name: str) -> Iterator[None]:
        with self.lock:
            self.running.append(name)
        try:
            yield
        finally:
            with self.lock:
                self.running.remove(name)

    def read(self, what: str) -> None:
        if self.running:
            message = f"{what} read while {self.running[-1]} ran"
            self.leaks.append(message)
            raise TruthLeak(message)


_PHASE = _Phase()
_GUARDED: dict[type, type] = {}
_SEALED: dict[type, type] = {}


def _guarded(cls: type) -> type:
    """`cls` whose every attribute read raises while car-side code runs."""
    if cls not in _GUARDED:
        def __getattribute__(self, name, _get=cls.__getattribute__, _cls=cls.__name__):  # noqa: N807
            _PHASE.read(f"{_cls}.{name}")
            return _get(self, name)
        _GUARDED[cls] = type(f"Guarded{cls.__name__}", (cls,),
                             {"__slots__": (), "__getattribute__": __getattribute__})
    return _GUARDED[cls]


def _sealed(cls: type, role: str) -> type:
    """`cls` whose every method, however it got there (the class's, an instance's own, one
    patched in later), runs as car-side code: its attribute reads hand out methods wrapped."""
    key = (cls, role)
    if key not in _SEALED:
        def __getattribute__(self, name, _get=cls.__getattribute__):  # noqa: N807
            value = _get(self, name)
            if isinstance(value, METHODS):
                return _car_side(value, f"{role} {cls.__name__}.{name}")
            return value
        namespace = {"__slots__": (), "__getattribute__": __getattribute__}
        if any("__call__" in vars(k) for k in cls.__mro__[:-1]):
            namespace["__call__"] = lambda self, *a, **k: _car_side(
                cls.__call__, f"{role} {cls.__name__}")(self, *a, **k)
        _SEALED[key] = type(f"Sealed{cls.__name__}", (cls,), namespace)
    return _SEALED[key]


METHODS = (types.MethodType, types.FunctionType, types.BuiltinMethodType, functools.partial)


def _car_side(function, where: str):
    @functools.wraps(function)
    def run(*args, **kwargs):
        with _PHASE.car_side(where):
            return function(*args, **kwargs)
    return run


class _GuardedEpisode(Episode):
    """The loop reads the truth through `self.truth`, never through its doors for tools."""

    __slots__ = ()

    def __getattribute__(self, name):
        _PHASE.read(f"Episode.{name}")
        return Episode.__getattribute__(self, name)

    @property
    def world(self):
        raise TruthLeak("Episode.world read in a guarded run (the loop reads episode.truth)")

    @property
    def scenario(self):
        raise TruthLeak("Episode.scenario read in a guarded run (the loop reads episode.truth)")

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._truth_guard.release()


def car_side(episode: Episode) -> dict[str, object]:
    """What perception, estimation and control are: the objects the truth must not reach."""
    driver = episode.driver
    parts = {f"detector {name}": d for name, d in driver.front.items()}
    parts |= {"reference detector": driver.reference, "estimator": driver.estimator,
              "controller": driver.controller, "odometry": driver.odometry,
              "roll filter": driver.roll}
    return parts


def truth_objects(episode: Episode) -> dict[int, str]:
    """id -> name of every object that holds or is the simulator's truth."""
    gate = episode.truth
    world, scenario = gate.world, gate.scenario
    named = {"the episode": episode, "the truth gate": gate, "the world": world,
             "world.data (MjData)": world.data, "world.model (MjModel)": world.model,
             "the car": world.car, "the road": world.road, "world.conditions": world.conditions,
             "world.layout": world.layout, "the scenario": scenario,
             "scenario.road": scenario.road, "scenario.conditions": scenario.conditions,
             "the renderer": episode.simulator.rig, "the sensors": episode.simulator.sensors,
             "the radar": episode.simulator.radar, "the traffic": world.traffic,
             "the metrics": episode.scorer.metrics, "the recorder": episode.recorder}
    named |= {f"road.segments[{i}]": s for i, s in enumerate(world.road.segments)}
    named |= {f"the {camera} effects": fx for camera, fx in episode.simulator.effects.items()}
    return {id(obj): name for name, obj in named.items() if obj is not None}


def _children(obj) -> Iterator[object]:
    """What `obj` holds: referents, less modules, classes, frames and functions' globals
    (those are the program, not what an object was handed); a function's closure and
    defaults and an instance's own class attributes count."""
    if isinstance(obj, types.FunctionType):
        yield from (c.cell_contents for c in obj.__closure__ or () if _filled(c))
        yield from obj.__defaults__ or ()
        yield from (obj.__kwdefaults__ or {}).values()
        return
    if isinstance(obj, types.MethodType):
        yield obj.__self__
        yield obj.__func__
        return
    for child in gc.get_referents(obj):
        if isinstance(child, (types.ModuleType, types.FrameType, type)):
            continue
        yield child
    for cls in type(obj).__mro__:
        if cls.__module__ not in ("builtins", "typing", "abc") and cls is not object:
            yield from vars(cls).values()


def _filled(cell) -> bool:
    try:
        cell.cell_contents  # noqa: B018 - an empty cell raises
    except ValueError:
        return False
    return True


def path_to_truth(root: object, root_name: str, truth: dict[int, str]) -> str | None:
    """The first chain of holdings from `root` to a truth object, or None."""
    seen, queue = {id(root)}, deque([(root, root_name)])
    while queue:
        obj, path = queue.popleft()
        for child in _children(obj):
            if id(child) in truth:
                return f"{path} -> {truth[id(child)]}"
            if id(child) in seen:
                continue
            seen.add(id(child))
            if len(seen) > MAX_REACH:
                raise TruthLeak(f"{root_name}: more than {MAX_REACH} objects reachable")
            queue.append((child, f"{path} -> {type(child).__name__}"))
    return None


def check_reach(episode: Episode) -> None:
    """Raise TruthLeak when any car-side object reaches a truth object."""
    truth = truth_objects(episode)
    for name, part in car_side(episode).items():
        path = path_to_truth(part, name, truth)
        if path is not None:
            raise TruthLeak(f"{path}: perception, estimation or control holds the truth")


class Guard:
    """One guarded episode: what was swapped, to put it back."""

    def __init__(self, episode: Episode) -> None:
        self.episode = episode
        self.swapped: list[tuple[object, type]] = []
        self.released = False

    def swap(self, obj: object, cls: type) -> None:
        self.swapped.append((obj, type(obj)))
        object.__setattr__(obj, "__class__", cls)

    def release(self) -> None:
        """Put the classes back, check reach again (what the run handed the car side), and
        raise any leak that something on the way swallowed."""
        if self.released:
            return
        self.released = True
        for obj, cls in reversed(self.swapped):
            object.__setattr__(obj, "__class__", cls)
        leaks, _PHASE.leaks[:] = list(_PHASE.leaks), []
        try:
            check_reach(self.episode)
        except TruthLeak as held:
            leaks.append(str(held))
        if leaks:
            raise TruthLeak("; ".join(leaks))


def guard_truth(episode: Episode) -> Guard:
    """Guard `episode` (module docstring) until it closes; raises TruthLeak at once when the
    car side already holds the truth."""
    check_reach(episode)
    _PHASE.leaks.clear()
    guard = Guard(episode)
    truth = episode.truth
    world, scenario = truth.world, truth.scenario
    readers = [truth, world, world.car, world.road, world.conditions, world.layout, scenario,
               scenario.road, scenario.conditions, *world.road.segments]
    for obj in {id(o): o for o in readers if o is not None}.values():
        guard.swap(obj, _guarded(type(obj)))
    for role, part in car_side(episode).items():
        guard.swap(part, _sealed(type(part), role))
    object.__setattr__(episode, "_truth_guard", guard)
    guard.swap(episode, _GuardedEpisode)
    return guard
