"""What the learned detectors share around their networks: reading a weights file safely and
running a forward pass on one torch thread. LaneNet (detectors/lanenet.py) and the row-anchor
observer (detectors/rowanchor.py) differ in their networks, not in these."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import torch


class WeightsError(ValueError):
    """A weights file that cannot become the detector's network; the message starts with the
    file's path."""

    def __init__(self, path: str | Path, why: str) -> None:
        super().__init__(f"{path}: {why}")
        self.path = str(path)


def read_weights_blob(path: str | Path, fmt: str, kind: str) -> dict:
    """The dict a weights file of format `fmt` holds (torch.load with weights_only=True), or
    `WeightsError` naming what is wrong: missing, empty, not torch's, or another format
    (`kind` names the expected one in the message, e.g. "LaneNet")."""
    p = Path(path)
    if not p.is_file():
        raise WeightsError(p, "no such weights file")
    if p.stat().st_size == 0:
        raise WeightsError(p, "weights file is empty")
    try:
        blob = torch.load(str(p), map_location="cpu", weights_only=True)
    except Exception as exc:  # noqa: BLE001 - any unpickling failure means the same thing
        # torch's own text advises weights_only=False, which we never do: name the kind only.
        raise WeightsError(p, "not a torch weights file (corrupt, truncated or another format; "
                              f"{type(exc).__name__})") from None
    if not isinstance(blob, dict) or blob.get("format") != fmt:
        raise WeightsError(p, f"not a {kind} weights file (expected format {fmt!r})")
    return blob


@contextmanager
def one_torch_thread() -> Iterator[None]:
    """One intra-op thread for the network: oneDNN's convolutions sum in an order that depends
    on the thread count (outputs differ by ~1e-7), and in a closed loop that grows into
    another episode; so a bench worker and the parent must run it alike. The network is small
    enough that a second thread hardly helps (`lanekeep perf` measures it), and where the other
    core is busy it hurts: each parallel call waits for the second thread's time slice. So
    every torch computation of a frame runs inside this, the batch's mirror flip too (outside,
    back-to-back frames took 3x as long, median, on a 2-core machine with its other core
    busy). torch's intra-op thread count belongs to the calling thread (OpenMP's setting is
    per thread; a new thread starts from the last count set anywhere), so this sets and
    restores the count of the thread it runs on: an episode's two detection threads
    (lanekeep/driver/detection.py) each run their network on one."""
    before = torch.get_num_threads()
    if before == 1:
        yield
        return
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)
