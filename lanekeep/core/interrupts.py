"""Stopping a run from outside: SIGTERM is handled as Ctrl-C, so both end a run the same way.

A job scheduler, `timeout` or `kill` sends SIGTERM, whose default action kills the process on
the spot: the recording loses its footer and no report is written. Under the CLI both signals
stop a run the same way, and the results so far are kept whichever way a run is stopped.

Where the code polls for it (an episode's step loop, inside `stop_point()`), a stop signal only
sets a flag and the loop ends after the step in progress: an exception raised at an arbitrary
point, in the middle of a render, a recording write or a queue operation, once left the
recording's finalisation hanging (a CI run of tests/core/test_interrupts.py). Elsewhere (building
the
world, the bench parent waiting for its workers) it raises KeyboardInterrupt. After the first
stop signal the later ones are ignored, so a forwarded copy or a second Ctrl-C cannot cut the
code that saves the results.

Bench workers ignore both signals while they wait for work (a signal there would kill the
worker and break the whole pool) and take them as a stop only while an episode runs; the
parent forwards a stop to them (`stop_children`), because SIGTERM, unlike a terminal's Ctrl-C,
reaches only the process it is sent to.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


_STOP = threading.Event()  # a stop signal arrived (this process)
_polling = 0  # > 0 while a loop that polls `stop_requested()` runs


def _on_stop_signal(signum, frame) -> None:  # noqa: ARG001 - the signal handler signature
    if _STOP.is_set():
        return  # already stopping: let the results be saved
    _STOP.set()
    if not _polling:
        raise KeyboardInterrupt(signal.Signals(signum).name)


def stop_requested() -> bool:
    """A stop signal arrived while `stop_signals_interrupt` was in force."""
    return _STOP.is_set()


@contextmanager
def stop_point() -> Iterator[None]:
    """Within the block a stop signal only sets the flag: the block's loop polls
    `stop_requested()` and ends between steps."""
    global _polling
    _polling += 1
    try:
        yield
    finally:
        _polling -= 1


@contextmanager
def stop_signals_interrupt() -> Iterator[None]:
    """Within the block SIGINT and SIGTERM stop the run: a flag where a loop polls for it,
    KeyboardInterrupt elsewhere; later signals are ignored (main thread only; elsewhere
    signals cannot be handled)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _STOP.clear()
    previous = {s: signal.signal(s, _on_stop_signal) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _STOP.clear()  # a later run in this process starts afresh


@contextmanager
def stop_signals_held() -> Iterator[None]:
    """Within the block SIGINT and SIGTERM are ignored: a file being finalised, a worker idle."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def ignore_stop_signals() -> None:
    """For a worker process's initializer: idle workers ignore stop signals."""
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)


def stop_children(sig: int = signal.SIGINT) -> list[int]:
    """Send `sig` to every live child process of this one; returns their pids."""
    pids = []
    for child in multiprocessing.active_children():
        if child.pid is not None:
            try:
                os.kill(child.pid, sig)
                pids.append(child.pid)
            except ProcessLookupError:
                pass
    return pids


def end_children(timeout_s: float) -> list[int]:
    """Wait up to `timeout_s` for the children to exit, then kill those left; their pids."""
    deadline = time.monotonic() + timeout_s
    children = multiprocessing.active_children()
    for child in children:
        child.join(max(0.0, deadline - time.monotonic()))
    killed = []
    for child in multiprocessing.active_children():
        child.kill()
        child.join(5.0)
        killed.append(child.pid)
    return killed
