"""A falsification's output folder: the journal of evaluated episodes and `results.parquet`.

As a sweep's (lanekeep/sweep/store.py, whose reasons hold here too): each finished episode is
one flushed JSON line of `episodes.jsonl` the moment it comes back, and the Parquet table is
rebuilt from it. An episode is known by the hash of its whole scenario table, so a search run
again in the same folder reads back every episode it already ran instead of running it: that
is how a search resumes (lanekeep/sweep/falsify_search.py replays the sampler). The first line
holds the spec's fingerprint and the search's sampler and seed: a folder of another search is
refused.

results.parquet: one row per episode: cell_id, phase ("search" or "shrink"), trial, one column
per parameter (its dotted key), seed, status, passed, margin, binding (the criterion that set
the margin), error, wall_s, lanekeep_version, then the metrics (as a sweep's).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from lanekeep.core.config_io import ConfigError
from lanekeep.core.files import atomic_path
from lanekeep.report.json_io import lanekeep_version, report_from_dict, strict
from lanekeep.sweep.falsify_objective import margin_of
from lanekeep.sweep.falsify_spec import FalsifySpec
from lanekeep.sweep.run import FINISHED, CellResult
from lanekeep.sweep.spec import report_metrics
from lanekeep.sweep.store import column_value

JOURNAL, RESULTS, SPEC_COPY = "episodes.jsonl", "results.parquet", "falsify.toml"
FIXED_COLUMNS = ("cell_id", "phase", "trial")
AFTER_KEYS = ("seed", "status", "passed", "margin", "binding", "error", "wall_s",
              "lanekeep_version")


class FalsifyStore:
    """The output folder of one search; opening one that holds it resumes it."""

    def __init__(self, out: str | Path, spec: FalsifySpec, search: dict) -> None:
        self.out, self.spec = Path(out), spec
        self.journal = self.out / JOURNAL
        self.version = lanekeep_version()
        self.head = {"fingerprint": spec.fingerprint(), "falsify": spec.name, **search}
        self._rows: dict[str, dict] = {}
        if self.journal.is_file():
            self._read()
        elif self.out.is_dir() and any(self.out.iterdir()):
            raise ConfigError("", "--out", f"{self.out} is not empty and holds no search "
                                           f"({JOURNAL} missing); give an empty or new folder")
        else:
            self.out.mkdir(parents=True, exist_ok=True)
            with open(self.journal, "w", encoding="utf-8") as f:
                f.write(json.dumps(self.head) + "\n")
            source = Path(spec.source)
            (self.out / SPEC_COPY).write_text(
                source.read_text(encoding="utf-8") if source.is_file() else "", encoding="utf-8")

    def _read(self) -> None:
        lines = self.journal.read_text(encoding="utf-8").splitlines()
        head = json.loads(lines[0]) if lines else {}
        if head != self.head:
            theirs = {k: head.get(k) for k in self.head if k != "fingerprint"}
            raise ConfigError("", "--out", f"{self.out} holds a different search ({theirs}; "
                                           f"or its spec or base scenario differs from "
                                           f"{self.spec.source}); give another folder")
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:  # a line cut short by a kill: that episode runs again
                continue
            self._rows[row["cell_id"]] = row

    def finished(self, cell_id: str) -> dict | None:
        """The row of an episode that need not run again (one that raised runs again)."""
        row = self._rows.get(cell_id)
        return row if row is not None and row["status"] in FINISHED else None

    def latest(self, cell_id: str) -> dict | None:
        """The latest row of an episode, finished or not (None: never ran)."""
        return self._rows.get(cell_id)

    def add(self, cell_id: str, phase: str, trial: int, values: tuple, seed: int,
            result: CellResult) -> dict:
        """Write one episode's row to the journal at once (flushed and synced)."""
        margin, binding = margin_of(result.report)
        row: dict[str, Any] = {"cell_id": cell_id, "phase": phase, "trial": trial}
        for key, value in zip(self.spec.keys, values, strict=True):
            row[key] = column_value(value)
        row.update(seed=seed, status=result.status,
                   passed=None if margin is None else margin >= 0, margin=margin,
                   binding=binding, error=result.error, wall_s=result.wall_s,
                   lanekeep_version=self.version)
        if result.report is not None:
            row.update(report_metrics(report_from_dict(result.report), self.spec.sweep.metrics))
        row = strict(row)
        with open(self.journal, "a", encoding="utf-8") as f:
            f.write(json.dumps(row, allow_nan=False) + "\n")
            f.flush()
            os.fsync(f.fileno())
        self._rows[cell_id] = row
        return row

    def rows(self) -> list[dict]:
        """Every episode's latest row, in the order they were first written."""
        return list(self._rows.values())

    def write(self) -> Path:
        """results.parquet from the journal (atomically)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        rows = self.rows()
        columns = list(dict.fromkeys([*FIXED_COLUMNS, *self.spec.keys, *AFTER_KEYS,
                                      *(k for r in rows for k in r)]))
        table = pa.table({c: pa.array([r.get(c) for r in rows]) for c in columns})
        path = self.out / RESULTS
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)
        return path
