"""Episode plots (PNG): offsets over time, MMAE probabilities (paper Fig. 12-13), top view."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class EpisodeTrace:
    """Per-step series kept for the plots (small: a few floats per step)."""

    model_names: list[str]
    time_s: list[float] = field(default_factory=list)
    truth_m: list[float] = field(default_factory=list)  # the car's offset (x = 0)
    truth_ahead_m: list[float] = field(default_factory=list)  # at the output's look-ahead
    ahead_x_m: float = 0.0
    reference_x_m: float = 0.0
    model_offsets_m: list[list[float]] = field(default_factory=list)
    track_offsets_m: list[list[float]] = field(default_factory=list)  # each model's own track
    fused_m: list[float] = field(default_factory=list)
    reference_m: list[float] = field(default_factory=list)
    probabilities: list[np.ndarray] = field(default_factory=list)
    path_xy: list[tuple[float, float]] = field(default_factory=list)

    def add(self, step) -> None:
        nan = float("nan")
        self.time_s.append(step.time_s)
        self.truth_m.append(step.truth_offset_m)
        self.truth_ahead_m.append(step.truth_output_m)
        self.ahead_x_m = step.output_x_m
        self.reference_x_m = step.reference_x_m
        self.model_offsets_m.append(
            [step.estimates[n].offset_m if step.estimates[n].valid else nan
             for n in self.model_names]
        )
        self.track_offsets_m.append(
            [nan if step.track_offsets_m.get(n) is None else step.track_offsets_m[n]
             for n in self.model_names]
        )
        self.fused_m.append(nan if step.output_offset_m is None else step.output_offset_m)
        self.reference_m.append(nan if step.reference_m is None else step.reference_m)
        self.probabilities.append(np.asarray(step.probabilities))
        self.path_xy.append(step.pose[:2])


def write_plots(trace: EpisodeTrace, road, out_dir: Path, title: str) -> list[Path]:
    """offsets.png, probabilities.png, top_view.png in `out_dir`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    t = np.asarray(trace.time_s)
    written = []

    fig, ax = plt.subplots(figsize=(10, 4.5))
    ax.plot(t, np.asarray(trace.truth_ahead_m) * 100, "k-", lw=2,
            label=f"ground truth at x = {trace.ahead_x_m:g} m (what the estimates measure)")
    ax.plot(t, np.asarray(trace.truth_m) * 100, "-", color="0.6", lw=1.2, label="car (x = 0)")
    offsets = np.asarray(trace.model_offsets_m) * 100
    tracks = np.asarray(trace.track_offsets_m) * 100
    for i, name in enumerate(trace.model_names):
        line, = ax.plot(t, offsets[:, i], lw=0.8, alpha=0.6, label=f"model {name} (detection)")
        ax.plot(t, tracks[:, i], "--", lw=1.2, color=line.get_color(),
                label=f"model {name} (own track)")
    ax.plot(t, np.asarray(trace.fused_m) * 100, lw=1.8, label="MMAE output")
    ax.plot(t, np.asarray(trace.reference_m) * 100, ":", lw=1.2,
            label=f"reference (rear, at x = {trace.reference_x_m:g} m)")
    ax.set(xlabel="time (s)", ylabel="offset (cm, + = car left of centre)", title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=3)
    fig.tight_layout()
    written.append(out_dir / "offsets.png")
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(10, 3.5))
    probs = np.asarray(trace.probabilities)
    for i, name in enumerate(trace.model_names):
        ax.plot(t, probs[:, i], lw=1.5, label=f"p({name})")
    ax.set(xlabel="time (s)", ylabel="model probability", ylim=(-0.02, 1.02),
           title=f"{title}: MMAE probabilities")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    written.append(out_dir / "probabilities.png")
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 7))
    s = np.linspace(0.0, road.length_m, 800)
    for b in range(road.n_lanes + 1):
        xy = road.position(s, np.full_like(s, road.boundary_r(b)))
        ax.plot(xy[:, 0], xy[:, 1], color="0.5", lw=0.8)
    path = np.asarray(trace.path_xy)
    if len(path):
        ax.plot(path[:, 0], path[:, 1], "r-", lw=1.5, label="driven path")
    ax.set_aspect("equal")
    ax.set(xlabel="x (m)", ylabel="y (m)", title=f"{title}: top view")
    ax.legend(fontsize=8)
    fig.tight_layout()
    written.append(out_dir / "top_view.png")
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)
    return written
