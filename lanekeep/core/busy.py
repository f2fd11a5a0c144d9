"""Whether the loop is using every core right now, for background work to stay out of the way.

Mesa's llvmpipe rasterises with a thread per core and waits for the slowest: a busy background
thread (the recorder's JPEG writer) made a 21 ms render take 56 ms on two cores. An episode's
detectors on two threads (lanekeep/driver/detection.py) fill the cores the same way. Sections
that do so run inside `all_cores_busy()`; background work waits for `CORES_FREE` before each
piece, and so runs in the loop's single-threaded stretches (camera effects, tracking, control,
physics, scoring). Sections may nest or overlap (a count, not a flag).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

CORES_FREE = threading.Event()  # set while no section that fills every core is running
CORES_FREE.set()
_LOCK = threading.Lock()
_busy = 0


@contextmanager
def all_cores_busy() -> Iterator[None]:
    """Marks a section that keeps every core busy (a render, the parallel detections)."""
    global _busy
    with _LOCK:
        _busy += 1
        CORES_FREE.clear()
    try:
        yield
    finally:
        with _LOCK:
            _busy -= 1
            if _busy == 0:
                CORES_FREE.set()
