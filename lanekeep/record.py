"""Episode recording. `NullRecorder` costs nothing; the rerun recorder logs every step."""

from __future__ import annotations

from typing import Any, Protocol


class Recorder(Protocol):
    """Receives each control step of an episode."""

    def log_step(self, episode: Any, step: Any) -> None: ...

    def close(self) -> None: ...


class NullRecorder:
    """Recording off: every call returns at once."""

    def log_step(self, episode: Any, step: Any) -> None:
        return None

    def close(self) -> None:
        return None
