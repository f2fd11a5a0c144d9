"""The entropy of a scenario's per-episode random streams: its seed and a key of its name.

Why the name: with the seed alone, every scenario run on seed 7 drew the same start jitter,
the same sensor noise, the same image effects and weather particles and the same traffic
timing, so a bench over scenarios on shared seeds summed correlated draws, not independent
ones. Folding in a stable key of the scenario's name gives each scenario its own streams
while the same scenario and seed still draw the same numbers in any process: the key comes
from SHA-256 of the name, never from Python's `hash()`, which is salted per process.

Which streams fold the name (each with its own tag, so one shifts no other):
  - the episode's generator (lanekeep/loop/episode.py): image effects, weather particles and
    camera noise, and the sensors' stream spawned from it;
  - the start and traffic-timing jitter (lanekeep/scenario/nuisance.py, NUISANCE_STREAM);
  - the drawn traffic (lanekeep/world/traffic_flow.py, TRAFFIC_STREAM).
The world's static details (textures, props, paint wear: lanekeep/world/) keep their
seed-only streams: they are the scene, not the drive. The sky (lanekeep/world/sky.py) folds the
name too: it does not depend on the road, so on a shared seed it was the one detail that made
different scenarios look the same.
"""

from __future__ import annotations

import hashlib

from lanekeep.scenario.schema import Scenario


def name_key(name: str) -> int:
    """A stable 32-bit key of a scenario's name: the first 4 bytes of its SHA-256."""
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:4], "little")


def stream_entropy(scenario: Scenario, *stream: int) -> list[int]:
    """The entropy of one of `scenario`'s per-episode streams, for `np.random.default_rng`:
    `[seed, name_key(name), *stream]` (no tags: the episode's generator)."""
    return [scenario.seed, name_key(scenario.name), *stream]
