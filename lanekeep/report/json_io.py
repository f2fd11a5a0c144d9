"""The JSON files lanekeep writes (`run --json`, `bench --json`, `perf --json`): strict JSON.

Strict means what every JSON parser accepts (RFC 8259): a value that is not a finite number
(an episode's NaN "no estimate", an infinity) is written as null, never as the NaN / Infinity
tokens Python's json module writes by default, which jq and a browser's JSON.parse reject.
So an episode's `min_ttc_s` is null when the car never closed on a vehicle ahead (inf in the
EpisodeReport; read back as inf), and `min_gap_m` null when it never had one ahead.

Each document carries where it came from (METADATA_KEYS):
  schema_version     SCHEMA_VERSION; raised when a key changes meaning or goes away
  lanekeep_version   the installed package's version ("unknown" if it is not installed)
  scenario_sha256    SHA-256 of the scenario file's bytes as read (a scenario built in memory,
                     whose `source` is no readable file: of its canonical form, the dataclass
                     repr with `source` blanked)
  seed               the seed the episode ran with (a `--seed` override, not the file's)
  reproducibility    the kernel settings in effect (renderer, torch, OpenCV, numpy and its BLAS,
                     the pinning variables; lanekeep/core/reproducibility.py): two reports agree
                     to the bit only where these agree

Files are written atomically: to a temporary file beside the target, then renamed over it, so
a reader never sees a half-written file and an interrupted write leaves the old file (or none).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import typing
from pathlib import Path
from typing import Any

from lanekeep.core.files import atomic_write
from lanekeep.core.reproducibility import settings_now
from lanekeep.scoring.metrics import CommonSteps, EpisodeReport, SourceReport

SCHEMA_VERSION = 2  # 2: bench documents summarise seeds (lanekeep/report/seed_summary.py)
METADATA_KEYS = ("schema_version", "lanekeep_version", "scenario_sha256", "seed",
                 "reproducibility")


def strict(obj: Any) -> Any:
    """`obj` with every non-finite float (NaN, +-inf) replaced by None, recursively; tuples
    become lists and NumPy scalars / arrays plain Python values."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {key: strict(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(value) for value in obj]
    if hasattr(obj, "tolist") and not isinstance(obj, (str, bytes)):  # numpy scalar or array
        return strict(obj.tolist())
    return obj


def dumps(obj: Any) -> str:
    """Strict JSON text of `obj` (indented); ValueError if something non-finite slipped by."""
    return json.dumps(strict(obj), indent=2, allow_nan=False) + "\n"


def write_json(path: str | Path, obj: Any) -> Path:
    """Write `obj` as strict JSON to `path` atomically (lanekeep/core/files.py); the folder
    is created if missing. Returns the path."""
    path = Path(path)
    text = dumps(obj)  # serialise first: a failure here leaves no file at all
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, text)


def lanekeep_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("lanekeep")
    except PackageNotFoundError:
        return "unknown"


def scenario_sha256(scenario) -> str:
    """SHA-256 (hex) of the scenario file's bytes; of the canonical dataclass repr (with
    `source` blanked) for a scenario that was not read from a file."""
    source = Path(scenario.source) if scenario.source else None
    if source is not None and source.is_file():
        return hashlib.sha256(source.read_bytes()).hexdigest()
    canonical = repr(dataclasses.replace(scenario, source=""))
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def with_metadata(document: dict, scenario, seed: int | None = None) -> dict:
    """`document` led by the METADATA_KEYS (which replace any of the document's own); `seed`
    defaults to the document's, else the scenario's."""
    head = {
        "schema_version": SCHEMA_VERSION,
        "lanekeep_version": lanekeep_version(),
        "scenario_sha256": scenario_sha256(scenario),
        "seed": seed if seed is not None else document.get("seed", scenario.seed),
        "reproducibility": settings_now(),
    }
    return {**head, **{k: v for k, v in document.items() if k not in head}}


def report_document(report: EpisodeReport, scenario) -> dict:
    """An episode's report as written to JSON: `report.to_dict()` led by the metadata, every
    non-finite number as None (strict JSON). A judged report (lanekeep/scoring/criteria.py) also
    says
    `passed`, beside its `criteria` verdicts (name, limit, value, passed) and `status`."""
    document = report.to_dict()
    if report.criteria:
        document["passed"] = report.passed
    return strict(with_metadata(document, scenario, seed=report.seed))


def _floats_back(cls: type, data: dict) -> dict:
    """`data` restricted to `cls`'s fields, None -> NaN in those typed float."""
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    return {key: (math.nan if value is None and hints[key] is float else value)
            for key, value in data.items() if key in names}


def report_from_dict(data: dict) -> EpisodeReport:
    """An EpisodeReport from `to_dict()` or from a report document read back from JSON (the
    metadata keys dropped, null floats NaN again, but a null `min_ttc_s` inf: never closing;
    a document from before the safety metrics gets their defaults)."""
    d = _floats_back(EpisodeReport, data)
    d["sources"] = {name: SourceReport(**_floats_back(SourceReport, values))
                    for name, values in d["sources"].items()}
    d["fused_vs_track"] = {name: CommonSteps(**_floats_back(CommonSteps, values))
                           for name, values in d.get("fused_vs_track", {}).items()}
    return EpisodeReport(**d)
