"""PNG plots of a sweep's results: each metric against each swept parameter, a heat map for two.

Line plots: one line per source (each detector's raw detections, its ":track" dashed, the
reference, the fused output; in the run plots' colours, lanekeep/report/palette.py) at the
mean over seeds, with the min-max band over seeds, so a reader sees both the trend and how
much a seed moves it. The other parameters' values each get their own panel (up to
MAX_PANELS, else they are pooled into the band). A two-parameter sweep also gets heat maps of
the mean over seeds, one panel per source.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

from lanekeep.report.palette import matplotlib_colour
from lanekeep.sweep.run import FINISHED
from lanekeep.sweep.spec import EPISODE_METRICS, SweepSpec

MAX_PANELS = 6


def _series(metric: str, rows: list[dict]) -> list[tuple[str, str]]:
    """(column, label) of each line of `metric`: the sources in the rows' column order."""
    if metric in EPISODE_METRICS:
        return [(metric, metric)]
    cols = dict.fromkeys(k for r in rows for k in r if k.startswith(f"{metric}@"))
    return [(c, c.split("@", 1)[1]) for c in cols]


def _finite(values: list[Any]) -> list[float]:
    return [float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)
            and math.isfinite(v)]


def _axis(values: tuple[Any, ...]) -> tuple[list[float], list[str] | None]:
    """x positions of a parameter's values: the numbers, or 0..n-1 with labels."""
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    labels = [v if isinstance(v, str) else json.dumps(v) for v in values]
    return list(range(len(values))), labels


def _match(row: dict, key: str, value: Any) -> bool:
    from lanekeep.sweep.store import column_value

    return row.get(key) == column_value(value)


def _file_name(*parts: str) -> str:
    return "__".join(re.sub(r"[^A-Za-z0-9_.-]+", "_", p) for p in parts) + ".png"


def plot_sweep(spec: SweepSpec, rows: list[dict], out_dir: str | Path) -> list[Path]:
    """Write every plot for the finished rows; returns the files."""
    import matplotlib

    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = [r for r in rows if r["status"] in FINISHED]
    written = []
    if not rows:
        return written
    for metric in spec.metrics:
        for i in range(len(spec.parameters)):
            written.append(_line_plot(spec, rows, metric, i, out_dir))
        if len(spec.parameters) == 2:
            written.append(_heat_map(spec, rows, metric, out_dir))
    return written


def _line_plot(spec: SweepSpec, rows: list[dict], metric: str, index: int,
               out_dir: Path) -> Path:
    import itertools

    import matplotlib.pyplot as plt

    param = spec.parameters[index]
    others = [p for j, p in enumerate(spec.parameters) if j != index]
    combos = list(itertools.product(*(p.values for p in others)))
    panels = combos if 1 < len(combos) <= MAX_PANELS else [None]
    xs, labels = _axis(param.values)
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels) + 1.5, 4.2),
                             sharey=True, squeeze=False, layout="constrained")
    series = _series(metric, rows)
    for ax, combo in zip(axes[0], panels, strict=True):
        subset = rows if combo is None else [
            r for r in rows if all(_match(r, p.key, v) for p, v in zip(others, combo,
                                                                         strict=True))]
        for n, (col, label) in enumerate(series):
            mean, low, high = [], [], []
            for value in param.values:
                vals = _finite([r.get(col) for r in subset if _match(r, param.key, value)])
                mean.append(sum(vals) / len(vals) if vals else math.nan)
                low.append(min(vals) if vals else math.nan)
                high.append(max(vals) if vals else math.nan)
            style = "--" if label.endswith(":track") else "-"
            line, = ax.plot(xs, mean, style, marker="o", label=label,
                            color=matplotlib_colour(label, n))
            ax.fill_between(xs, low, high, color=line.get_color(), alpha=0.15, linewidth=0)
        if labels is not None:
            ax.set_xticks(xs, labels, rotation=20, ha="right")
        ax.set_xlabel(param.key)
        ax.grid(True, alpha=0.3)
        if combo is not None:
            ax.set_title(", ".join(f"{p.key} = {v}" for p, v in zip(others, combo,
                                                                    strict=True)), fontsize=9)
    axes[0][0].set_ylabel(metric)
    pooled = " (other parameters pooled)" if others and panels == [None] else ""
    fig.suptitle(f"{spec.name}: {metric} vs {param.key}: mean over {len(spec.seeds)} seeds, "
                 f"band = min-max{pooled}", fontsize=10)
    if len(series) > 1:
        axes[0][-1].legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
    path = out_dir / _file_name(metric, "vs", param.key)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _heat_map(spec: SweepSpec, rows: list[dict], metric: str, out_dir: Path) -> Path:
    import matplotlib.pyplot as plt
    import numpy as np

    py, px = spec.parameters  # rows: the first parameter, columns: the second
    series = [s for s in _series(metric, rows) if not s[1].endswith(":track")]
    fig, axes = plt.subplots(1, len(series), figsize=(3.6 * len(series) + 1.2, 3.8),
                             squeeze=False, layout="constrained")
    grids = []
    for col, _ in series:
        grid = np.full((len(py.values), len(px.values)), np.nan)
        for i, vy in enumerate(py.values):
            for j, vx in enumerate(px.values):
                vals = _finite([r.get(col) for r in rows
                                if _match(r, py.key, vy) and _match(r, px.key, vx)])
                if vals:
                    grid[i, j] = sum(vals) / len(vals)
        grids.append(grid)
    finite = np.concatenate([g[np.isfinite(g)] for g in grids]) if grids else np.array([])
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    for ax, (_, label), grid in zip(axes[0], series, grids, strict=True):
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=vmin,
                          vmax=vmax)
        for (i, j), v in np.ndenumerate(grid):
            ax.text(j, i, "-" if math.isnan(v) else f"{v:.3g}", ha="center", va="center",
                    color="w" if not math.isnan(v) and v < (vmin + vmax) / 2 else "k",
                    fontsize=8)
        _, xl = _axis(px.values)
        _, yl = _axis(py.values)
        ax.set_xticks(range(len(px.values)), xl or [f"{v:g}" for v in px.values],
                      rotation=20, ha="right", fontsize=8)
        ax.set_yticks(range(len(py.values)), yl or [f"{v:g}" for v in py.values], fontsize=8)
        ax.set_xlabel(px.key)
        ax.set_ylabel(py.key)
        ax.set_title(label, fontsize=9)
    fig.colorbar(image, ax=axes[0].tolist(), label=metric)
    fig.suptitle(f"{spec.name}: {metric}, mean over {len(spec.seeds)} seeds", fontsize=10)
    path = out_dir / _file_name("heatmap", metric)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
