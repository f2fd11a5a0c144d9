"""A sweep's output folder: the journal of finished cells, `results.parquet`, `summary.json`.

Why a journal: Parquet files cannot be appended to, and a sweep of thousands of episodes must
keep each cell the moment it finishes (a crash or Ctrl-C loses nothing finished). Each result
is one JSON line in `cells.jsonl`, flushed; the Parquet table and the summary are rebuilt from
it (the latest line of each cell wins, so a retried cell replaces its failure). The journal's
first line holds the sweep's fingerprint: an `--out` that holds another sweep is refused.

Files: sweep.toml (a copy of the sweep file), cells.jsonl, results.parquet (one row per cell:
cell_id, one column per parameter (its dotted key; an array value as JSON text), seed, status,
passed, error, wall_s, lanekeep_version, then the metrics, per source "METRIC@SOURCE"),
summary.json (counts, failures, and each parameter combination's mean, sd, 95% t interval
(lanekeep/scoring/statistics.py; null below two seeds), min and max over seeds).
"""

from __future__ import annotations

import json
import math
import os
import statistics
from pathlib import Path
from typing import Any

from lanekeep.core.config_io import ConfigError
from lanekeep.core.files import atomic_path
from lanekeep.report.json_io import lanekeep_version, strict, write_json
from lanekeep.scoring.statistics import spread as seed_spread
from lanekeep.sweep.run import FINISHED, CellResult
from lanekeep.sweep.spec import Cell, SweepSpec, report_metrics

JOURNAL, RESULTS, SUMMARY, SWEEP_COPY = "cells.jsonl", "results.parquet", "summary.json", \
    "sweep.toml"
FIXED_COLUMNS = ("cell_id", "seed", "status", "passed", "error", "wall_s", "lanekeep_version")


def column_value(value: Any) -> Any:
    """A parameter's value as a table cell: scalars as they are, arrays and tables as JSON."""
    if isinstance(value, (list, dict, tuple)):
        return json.dumps(value, sort_keys=True)
    return value


class SweepStore:
    """The output folder of one sweep; opening an existing one resumes it."""

    def __init__(self, out: str | Path, spec: SweepSpec) -> None:
        self.out, self.spec = Path(out), spec
        self.journal = self.out / JOURNAL
        self.version = lanekeep_version()
        self._rows: dict[str, dict] = {}
        if self.journal.is_file():
            self._read()
        elif self.out.is_dir() and any(self.out.iterdir()):
            raise ConfigError("", "--out", f"{self.out} is not empty and holds no sweep "
                                           f"({JOURNAL} missing); give an empty or new folder")
        else:
            self.out.mkdir(parents=True, exist_ok=True)
            with open(self.journal, "w", encoding="utf-8") as f:
                f.write(json.dumps({"fingerprint": spec.fingerprint(), "sweep": spec.name})
                        + "\n")
            text = Path(spec.source).read_text(encoding="utf-8") if Path(
                spec.source).is_file() else ""
            (self.out / SWEEP_COPY).write_text(text, encoding="utf-8")

    def _read(self) -> None:
        lines = self.journal.read_text(encoding="utf-8").splitlines()
        head = json.loads(lines[0]) if lines else {}
        if head.get("fingerprint") != self.spec.fingerprint():
            raise ConfigError("", "--out", f"{self.out} holds a different sweep "
                                           f"({head.get('sweep', '?')!r}: its file or base "
                                           f"scenario differs from {self.spec.source}); give "
                                           f"another folder")
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:  # a line cut short by a kill: that cell runs again
                continue
            self._rows[row["cell_id"]] = row

    def finished_ids(self) -> set[str]:
        """Cells that need not run again (failed and interrupted ones do)."""
        return {cid for cid, row in self._rows.items() if row["status"] in FINISHED}

    def row(self, cell: Cell, result: CellResult) -> dict:
        row: dict[str, Any] = {"cell_id": cell.cell_id}
        for key, value in zip(self.spec.keys, cell.values, strict=True):
            row[key] = column_value(value)
        report = result.report
        row.update(seed=cell.seed, status=result.status,
                   passed=None if report is None else all(
                       v["passed"] for v in report.get("criteria", ())),
                   error=result.error, wall_s=result.wall_s, lanekeep_version=self.version)
        if report is not None:
            from lanekeep.report.json_io import report_from_dict

            row.update(report_metrics(report_from_dict(report), self.spec.metrics))
        return strict(row)

    def add(self, cell: Cell, result: CellResult) -> dict:
        """Write one cell's row to the journal at once (flushed and synced)."""
        row = self.row(cell, result)
        with open(self.journal, "a", encoding="utf-8") as f:
            f.write(json.dumps(row, allow_nan=False) + "\n")
            f.flush()
            os.fsync(f.fileno())
        self._rows[cell.cell_id] = row
        return row

    def rows(self) -> list[dict]:
        """The latest row of each cell, in the sweep's cell order (cells not run: none)."""
        order = {c.cell_id: i for i, c in enumerate(self.spec.cells())}
        return sorted((r for cid, r in self._rows.items() if cid in order),
                      key=lambda r: order[r["cell_id"]])

    def write(self) -> tuple[Path, Path]:
        """results.parquet and summary.json from the journal (atomically each)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        rows = self.rows()
        columns = list(dict.fromkeys(
            [FIXED_COLUMNS[0], *self.spec.keys, *FIXED_COLUMNS[1:],
             *(k for r in rows for k in r)]))
        table = pa.table({c: pa.array([r.get(c) for r in rows]) for c in columns})
        results = self.out / RESULTS
        with atomic_path(results) as tmp:
            pq.write_table(table, tmp)
        return results, write_json(self.out / SUMMARY, self.summary(rows))

    def summary(self, rows: list[dict]) -> dict:
        spec = self.spec
        counts: dict[str, int] = {}
        for r in rows:
            counts[r["status"]] = counts.get(r["status"], 0) + 1
        total = len(spec.cells())
        metric_cols = [c for c in dict.fromkeys(k for r in rows for k in r)
                       if c not in FIXED_COLUMNS and c not in spec.keys]
        groups: dict[str, list[dict]] = {}
        for r in rows:
            if r["status"] in FINISHED:
                key = json.dumps([r[k] for k in spec.keys])
                groups.setdefault(key, []).append(r)
        by_parameters = []
        for key, members in groups.items():
            stats = {}
            for c in metric_cols:
                values = [m[c] for m in members if isinstance(m.get(c), (int, float))
                          and math.isfinite(m[c])]
                spread = seed_spread(values)
                stats[c] = ({"mean": statistics.fmean(values), "sd": spread.sd,
                             "ci95": list(spread.ci95), "min": min(values),
                             "max": max(values)} if values else None)
            by_parameters.append({"parameters": dict(zip(spec.keys, json.loads(key),
                                                         strict=True)),
                                  "seeds": len(members), "metrics": stats})
        walls = [r["wall_s"] for r in rows if r["status"] in FINISHED]
        return {
            "sweep": spec.name, "file": spec.source, "base": spec.base,
            "fingerprint": spec.fingerprint(), "lanekeep_version": self.version,
            "parameters": {p.key: list(p.values) for p in spec.parameters},
            "seeds": list(spec.seeds), "seconds": spec.seconds, "metrics": list(spec.metrics),
            "render": list(spec.render) if spec.render else None,
            "cells": total, "cells_recorded": len(rows), "status": counts,
            "cells_missing": total - sum(counts.get(s, 0) for s in FINISHED),
            "cell_wall_s": ({"mean": statistics.fmean(walls), "median": statistics.median(walls),
                             "max": max(walls)} if walls else None),
            "failed": [{"cell_id": r["cell_id"], "seed": r["seed"], "status": r["status"],
                        "parameters": {k: r[k] for k in spec.keys}, "error": r["error"]}
                       for r in rows if r["status"] not in FINISHED],
            "by_parameters": by_parameters,
        }
