"""Stopping a run from outside: SIGTERM is handled as Ctrl-C, so both end a run the same way.

A job scheduler, `timeout` or `kill` sends SIGTERM, whose default action kills the process on
the spot: the recording loses its footer and no report is written. Turned into
KeyboardInterrupt, it reaches the code that already handles Ctrl-C (`Episode.run` returns the
partial report, the recorder finalises its file, `bench` collects its workers), so the
results so far are kept whichever way a run is stopped.

Bench workers ignore both signals while they wait for work (a signal there would kill the
worker and break the whole pool) and take them as an interrupt only while an episode runs;
the parent forwards a stop to them (`stop_children`), because SIGTERM, unlike a terminal's
Ctrl-C, reaches only the process it is sent to.
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


def _raise_interrupt(signum, frame) -> None:  # noqa: ARG001 - the signal handler signature
    # Once: a second signal (a forwarded copy, an impatient second Ctrl-C) must not cut the
    # code that is saving the results of the first.
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)
    raise KeyboardInterrupt(signal.Signals(signum).name)


@contextmanager
def stop_signals_interrupt() -> Iterator[None]:
    """Within the block the first SIGINT or SIGTERM raises KeyboardInterrupt and later ones
    are ignored (main thread only; elsewhere signals cannot be handled)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _raise_interrupt) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


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
