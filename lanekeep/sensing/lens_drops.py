"""Where the rain drops on a camera's lens are at a given time of the drive.

A lens in the rain does not keep one set of drops: drops land, cling for a few seconds (the
small ones hardly move, the big ones creep down under their weight) and are blown off or run
away, and new ones land elsewhere. So the drops are a function of the drive's time, not of how
many frames were made: a snapshot at mid-drive shows the drops of mid-drive, not those of the
start (before, both showed the same 14 drops at the same pixels).

Each of the lens's n places ("slots") holds one drop at a time, a sequence of drops one after
another. The first drop of every slot is where the episode's generator put it at time 0 (the
draws `Weather` always made); its age then, and every later drop (landing place, size, how long
it stays), come from a stream of the slot's own, derived from the episode's seed
(DROP_STREAM), so that no other random draw of the episode moves and the drops at time t do not
depend on which frames were made before.
"""

from __future__ import annotations

import bisect

import numpy as np

DROP_STREAM = 0xD209  # spawn-key word of the drops' own streams (far from spawn()'s 0, 1, ...)
DROP_RADIUS_PX = (8.0, 30.0)  # at 720 rows
DROP_LIFE_S = (3.0, 10.0)  # how long a drop stays on the lens
DROP_CREEP_PX_S = 20.0  # how fast the largest drop creeps down (at 720 rows); ~ radius cubed
WOBBLE_PX = 0.75  # each frame a drop shivers in the airflow by up to this (at 720 rows)


def drop_streams(rng: np.random.Generator, camera: int, n: int) -> list[np.random.Generator]:
    """The slots' own generators: children of the episode generator's seed sequence under
    (DROP_STREAM, camera, slot) that spawn() never makes; drawing from them moves nothing else."""
    seq = getattr(rng.bit_generator, "seed_seq", None)
    entropy = getattr(seq, "entropy", None)
    key = tuple(getattr(seq, "spawn_key", ())) if entropy is not None else ()
    return [np.random.default_rng(np.random.SeedSequence(
        0 if entropy is None else entropy, spawn_key=(*key, DROP_STREAM, camera, slot)))
        for slot in range(n)]


class LensDrops:
    """The drops of one camera's lens over the drive; `at(t)` gives those on it at time t."""

    def __init__(self, first: np.ndarray, streams: list[np.random.Generator], width: int,
                 height: int) -> None:
        """`first`: (n, 3) x, y, radius (px) of each slot's drop at time 0."""
        self.width, self.height = width, height
        self.scale = height / 720.0
        self._streams = streams
        self.slots = range(len(streams))
        # per slot: landing times, and (x, y at landing, radius, life) of its drops in order
        self._land: list[list[float]] = []
        self._drops: list[list[tuple[float, float, float, float]]] = []
        for (x, y, r), stream in zip(first, streams, strict=True):
            life = float(stream.uniform(*DROP_LIFE_S))
            age = float(stream.uniform(0.0, life))
            self._land.append([-age])
            self._drops.append([(float(x), float(y) - self._creep(r) * age, float(r), life)])

    def _creep(self, radius_px: float) -> float:
        """A drop's downward speed (px/s): heavier drops overcome the lens's grip faster."""
        big = DROP_RADIUS_PX[1] * self.scale
        return DROP_CREEP_PX_S * self.scale * min(radius_px / big, 1.0) ** 3

    def _extend(self, slot: int, t: float) -> None:
        """Draw the slot's next drops until one is on the lens at time t."""
        land, drops, stream = self._land[slot], self._drops[slot], self._streams[slot]
        while land[-1] + drops[-1][3] <= t:
            land.append(land[-1] + drops[-1][3])
            x, y = stream.uniform(0.0, self.width), stream.uniform(0.0, self.height)
            r = stream.uniform(*DROP_RADIUS_PX) * self.scale
            drops.append((float(x), float(y), float(r), float(stream.uniform(*DROP_LIFE_S))))

    def at(self, t: float, wobble: np.ndarray | None = None) -> np.ndarray:
        """(k, 3) x, y, radius of the drops on the lens at time t (s) that lie in the frame;
        `wobble` (n,) in [0, 1) shifts each slot's drop by up to +-WOBBLE_PX this frame."""
        out = []
        for slot in range(len(self._drops)):
            self._extend(slot, t)
            k = bisect.bisect_right(self._land[slot], t) - 1
            if k < 0:
                continue
            x, y, r, _ = self._drops[slot][k]
            y += self._creep(r) * (t - self._land[slot][k])
            if wobble is not None:
                y += (2.0 * wobble[slot] - 1.0) * WOBBLE_PX * self.scale
            if y - r < self.height:
                out.append((x, y, r))
        return np.array(out, float).reshape(-1, 3)
