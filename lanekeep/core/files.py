"""One atomic writer: a file is complete or absent, never half-written.

Every file the package writes for a reader to find later (JSON reports, JUnit XML, parquet
tables, camera files, cached sets, overlays, dataset shards) goes through here: the bytes go to
a hidden temporary file in the same folder (a rename across folders could cross file systems,
and only a rename within one is atomic), which `os.replace` then puts in place. A failure
removes the temporary file and leaves any file already at `path` as it was. New files get mode
0666 & ~umask, as `open` gives them. `folder_problem` says, before anything runs, why a folder
could not take them.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def temp_beside(path: str | Path, suffix: str | None = None) -> Path:
    """A new, empty file next to `path` (created exclusively, mode 0666 & ~umask) whose name
    ends in `suffix` (default: `path`'s), for writers that choose a format by it (OpenCV,
    NumPy)."""
    path = Path(path)
    suffix = path.suffix if suffix is None else suffix
    while True:
        tmp = path.parent / f".{path.stem}.{secrets.token_hex(4)}.tmp{suffix}"
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return tmp
        except FileExistsError:
            continue


class PendingFile:
    """A temporary file beside `path` that becomes `path` on `commit()`, or goes on
    `discard()`: for a writer that fills a file over time (a video, frame by frame)."""

    def __init__(self, path: str | Path, suffix: str | None = None) -> None:
        self.path = Path(path)
        self.tmp = temp_beside(self.path, suffix)

    def commit(self) -> None:
        try:
            os.replace(self.tmp, self.path)
        finally:
            self.tmp.unlink(missing_ok=True)

    def discard(self) -> None:
        self.tmp.unlink(missing_ok=True)


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside `path` to write to; on leaving the block without an exception
    it replaces `path`, with one it is removed (and `path` is untouched)."""
    pending = PendingFile(path)
    try:
        yield pending.tmp
    except BaseException:
        pending.discard()
        raise
    pending.commit()


def atomic_write(path: str | Path, data: bytes | str, sync: bool = True) -> Path:
    """Write `data` (str: as UTF-8) to `path` atomically, flushed to the disk first when
    `sync` (a report that survives a crash right after). Returns the path."""
    payload = data.encode("utf-8") if isinstance(data, str) else data
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(payload)
        f.flush()
        if sync:
            os.fsync(f.fileno())
    return path


def folder_problem(folder: Path) -> str | None:
    """Why `folder` could not become a folder to write in, found without creating anything."""
    if folder.exists() and not folder.is_dir():
        return f"{folder} is not a folder"
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"cannot create the folder {folder}: {existing} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot write in {existing}"
    return None
