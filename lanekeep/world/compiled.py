"""The compiled worlds of this process, kept so that building a scenario again costs a copy.

A world is a pure function of its scenario (every field, the seed and the file it came from)
and its layout: `build_spec` reads no file but the car's MJCF, and draws every texture, prop
and shadow from generators seeded by the scenario. So a second build of the same scenario
can start from a copy of the first's compiled model (`mujoco.MjModel` copies in ~30 ms)
instead of generating and compiling it again (1-2.5 s). Who builds the same scenario more
than once in a process: a test suite (on 2026-12-02, 174 of the 464 world builds of CI's test
tier were repeats within a process, 201 of its 685 build-seconds), a Gymnasium or dm_env
environment reset to the same seed, a script that compares two drivers on one world.

What is kept is never handed out: every `take` gives a copy of the model (an episode moves
the street lights and hides geoms while it renders; the next world must not see that) and of
the conditions. A bench's episodes differ by seed and build once each, as before. Code that
changes what a build makes while the process runs (a test patching a module's constant)
clears the cache first, or builds with it off (`CompiledWorlds.disabled`).
"""

from __future__ import annotations

import contextlib
import copy
import threading
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass

import mujoco

from lanekeep.scenario.schema import Scenario
from lanekeep.world.parts import ConditionsInfo, WorldLayout

# Worlds kept per process. Each is about 30 MB (clear_curve's model, mostly its textures),
# and a bench worker or an environment reset to new seeds never asks for one again, so few:
# replayed over CI's build log (2026-12-02), two per process reuse 93 builds, four 102, eight
# 110, of the 174 repeats.
SLOTS = 2


@dataclass(frozen=True)
class Compiled:
    """What `build` compiled for a scenario, before a world's own state (data, traffic)."""

    model: mujoco.MjModel
    marking_names: dict[str, int]
    conditions: ConditionsInfo

    def copied(self) -> Compiled:
        """An independent copy: changing it leaves this one as it is."""
        return Compiled(copy.copy(self.model), dict(self.marking_names),
                        copy.deepcopy(self.conditions))


def world_key(scenario: Scenario, layout: WorldLayout | None) -> str:
    """Everything a build depends on, as text: the scenario's dataclass repr (every field, the
    source file's path included) and the layout's."""
    return f"{scenario!r}|{layout!r}"


class CompiledWorlds:
    """The `slots` most recently used compiled worlds by key, thread-safe; `take` and `keep`
    copy."""

    def __init__(self, slots: int = SLOTS) -> None:
        self._slots = slots
        self._lock = threading.Lock()
        self._kept: OrderedDict[str, Compiled] = OrderedDict()
        self._off = 0  # depth of `disabled` blocks

    def take(self, key: str) -> Compiled | None:
        """A copy of the world kept under `key`, or None."""
        with self._lock:
            kept = None if self._off else self._kept.get(key)
            if kept is None:
                return None
            self._kept.move_to_end(key)
        return kept.copied()

    def keep(self, key: str, compiled: Compiled) -> None:
        """Keep a copy of `compiled` under `key` (dropping the least recently used)."""
        if self._off or self._slots <= 0:
            return
        kept = compiled.copied()
        with self._lock:
            self._kept[key] = kept
            self._kept.move_to_end(key)
            while len(self._kept) > self._slots:
                self._kept.popitem(last=False)

    def clear(self) -> None:
        """Forget every kept world."""
        with self._lock:
            self._kept.clear()

    def __len__(self) -> int:
        with self._lock:
            return len(self._kept)

    @contextlib.contextmanager
    def disabled(self) -> Iterator[None]:
        """Within the block every build is made afresh and nothing is kept; what was kept
        before is forgotten (it may no longer be what a build would make)."""
        with self._lock:
            self._off += 1
            self._kept.clear()
        try:
            yield
        finally:
            with self._lock:
                self._off -= 1


COMPILED_WORLDS = CompiledWorlds()  # `build`'s
