"""Episode plots (PNG): offsets against the truth each estimate measures, errors over time per
source, MMAE probabilities (paper Fig. 12-13), the top view.

Every estimate reports its offset at its own look-ahead (a detector at its ground window's
reference distance, the fused output and the tracks at the output's look-ahead, the rear
reference behind the car), so one truth curve cannot be the yardstick of all of them: each
source is drawn beside the truth at its own look-ahead, and its error (estimate - that truth)
is plotted directly; these are the errors the report's table scores. Names and colours match
the report and the recording (lanekeep/report/record.py): the MMAE output is "fused".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lanekeep.report.palette import COLOURS, FUSED, REFERENCE, TRUTH, colour

FILES = ("offsets.png", "errors.png", "probabilities.png", "top_view.png")


def _rgb(name: str, models: list[str]) -> tuple[float, float, float]:
    """The recording's colour of a source, for matplotlib."""
    r, g, b = colour(name, models.index(name) if name in models else 0)
    return r / 255, g / 255, b / 255


@dataclass
class EpisodeTrace:
    """Per-step series kept for the plots (a few floats per step); the truth at each
    estimate's own look-ahead is the step's own (`StepResult.truth`, computed once by scoring
    from the pose its frames were taken at)."""

    model_names: list[str]
    time_s: list[float] = field(default_factory=list)
    truth_m: list[float] = field(default_factory=list)  # the car's offset (x = 0)
    truth_ahead_m: list[float] = field(default_factory=list)  # at the output's look-ahead
    ahead_x_m: float = 0.0
    reference_x_m: float = 0.0
    model_x_m: list[float] = field(default_factory=list)  # each model's last look-ahead
    model_offsets_m: list[list[float]] = field(default_factory=list)
    model_truth_m: list[list[float]] = field(default_factory=list)  # truth at each one's x
    track_offsets_m: list[list[float]] = field(default_factory=list)  # each model's own track
    fused_m: list[float] = field(default_factory=list)
    reference_m: list[float] = field(default_factory=list)
    reference_truth_m: list[float] = field(default_factory=list)
    probabilities: list[np.ndarray] = field(default_factory=list)
    residuals_m: list[np.ndarray] = field(default_factory=list)  # the MMAE's, NaN: not compared
    path_xy: list[tuple[float, float]] = field(default_factory=list)

    def add(self, step) -> None:
        nan = float("nan")
        self.time_s.append(step.time_s)
        self.truth_m.append(step.truth.car_offset_m)
        self.truth_ahead_m.append(step.truth.offset_at(step.output_x_m))
        self.ahead_x_m = step.output_x_m
        self.reference_x_m = step.reference_x_m
        estimates = [step.estimates[n] for n in self.model_names]
        self.model_x_m = [float(e.x_m) for e in estimates]
        xs = [*self.model_x_m, float(step.reference_x_m)]
        truths = [step.truth.offset_at(x) for x in xs]
        self.model_truth_m.append(truths[:-1])
        self.reference_truth_m.append(truths[-1])
        self.model_offsets_m.append([e.offset_m if e.valid else nan for e in estimates])
        self.track_offsets_m.append(
            [nan if step.track_offsets_m.get(n) is None else step.track_offsets_m[n]
             for n in self.model_names]
        )
        self.fused_m.append(nan if step.output_offset_m is None else step.output_offset_m)
        self.reference_m.append(nan if step.reference_m is None else step.reference_m)
        self.probabilities.append(np.asarray(step.probabilities))
        self.residuals_m.append(np.asarray(step.mmae_residuals_m, dtype=float))
        self.path_xy.append(step.pose[:2])

    def errors_cm(self) -> dict[str, np.ndarray]:
        """Per source (the report's names), estimate - truth at its own look-ahead (cm)."""
        out = {}
        offsets, truths = np.asarray(self.model_offsets_m), np.asarray(self.model_truth_m)
        tracks, ahead = np.asarray(self.track_offsets_m), np.asarray(self.truth_ahead_m)
        for i, name in enumerate(self.model_names):
            out[name] = (offsets[:, i] - truths[:, i]) * 100
            out[f"{name}:track"] = (tracks[:, i] - ahead) * 100
        out[FUSED] = (np.asarray(self.fused_m) - ahead) * 100
        out[REFERENCE] = (np.asarray(self.reference_m) - np.asarray(self.reference_truth_m)) * 100
        return out


def plot_title(scenario) -> str:
    """Scenario, seed and the settings that change the numbers, for every figure's title."""
    est = scenario.estimation
    return (f"{scenario.name} (seed {scenario.seed}, mode {est.mode}, front "
            f"{'+'.join(est.front_detectors)}, reference {est.reference_detector})")


def write_plots(trace: EpisodeTrace, road, out_dir: Path, title: str) -> list[Path]:
    """offsets.png, errors.png, probabilities.png, top_view.png in `out_dir`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    t = np.asarray(trace.time_s)
    models = trace.model_names
    written = []

    def save(fig, name: str) -> None:
        fig.tight_layout()
        written.append(out_dir / name)
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)

    # offsets: one panel per source, each beside the truth at its own look-ahead
    offsets, truths = np.asarray(trace.model_offsets_m), np.asarray(trace.model_truth_m)
    tracks = np.asarray(trace.track_offsets_m)
    panels = [(f"{name} (detection, x = {trace.model_x_m[i]:g} m)", name, offsets[:, i],
               truths[:, i]) for i, name in enumerate(models)]
    panels.append((f"{FUSED} (MMAE output, x = {trace.ahead_x_m:g} m)", FUSED,
                   np.asarray(trace.fused_m), np.asarray(trace.truth_ahead_m)))
    panels.append((f"{REFERENCE} (rear, x = {trace.reference_x_m:g} m)", REFERENCE,
                   np.asarray(trace.reference_m), np.asarray(trace.reference_truth_m)))
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 2.0 * len(panels) + 1), sharex=True)
    for ax, (label, name, values, truth) in zip(axes, panels, strict=True):
        ax.plot(t, truth * 100, "-", color=_rgb(TRUTH, models), lw=2.2,
                label="truth at the same look-ahead")
        ax.plot(t, values * 100, ".-", color=_rgb(name, models), lw=1.4, ms=4, label=name)
        if name in models:
            i = models.index(name)
            ax.plot(t, tracks[:, i] * 100, "--", color=_rgb(name, models), lw=1.0,
                    label=f"{name}:track (x = {trace.ahead_x_m:g} m)")
        ax.set_title(label, fontsize=9, loc="left")
        ax.set_ylabel("offset (cm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"{title}\nlateral offsets (+ = car left of the lane centre)", fontsize=10)
    save(fig, "offsets.png")

    # errors over time, one panel per source: the numbers the report's table summarises
    errors = trace.errors_cm()
    fig, axes = plt.subplots(len(errors), 1, figsize=(10, 1.5 * len(errors) + 1), sharex=True)
    for ax, (name, err) in zip(axes, errors.items(), strict=True):
        base = name.split(":")[0]
        rmse = float(np.sqrt(np.nanmean(err ** 2))) if np.isfinite(err).any() else float("nan")
        ax.plot(t, err, ".", color=_rgb(base, models), lw=1.3, ms=4,
                ls="--" if ":" in name else "-")
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_title(f"{name}: RMSE {rmse:.1f} cm", fontsize=9, loc="left")
        ax.set_ylabel("error (cm)")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"{title}\noffset error over time (estimate - truth at its look-ahead)",
                 fontsize=10)
    save(fig, "errors.png")

    fig, (ax, ax_r) = plt.subplots(2, 1, figsize=(10, 6), sharex=True,
                                   gridspec_kw={"height_ratios": [3, 2]})
    probs = np.asarray(trace.probabilities)
    residuals = np.asarray(trace.residuals_m) * 100
    for i, name in enumerate(models):
        ax.plot(t, probs[:, i], lw=1.5, color=_rgb(name, models), label=f"p({name})")
        ax_r.plot(t, residuals[:, i], lw=1.0, color=_rgb(name, models), label=name)
    ax.set(ylabel="model probability", ylim=(-0.02, 1.02))
    ax.set_title(f"{title}\nMMAE probabilities, and the residuals they come from", fontsize=10)
    ax_r.set(xlabel="time (s)", ylabel="reference - model (cm)")
    for a in (ax, ax_r):
        a.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, "probabilities.png")

    fig, ax = plt.subplots(figsize=(7, 7))
    s = np.linspace(0.0, road.length_m, 800)
    for b in range(road.n_lanes + 1):
        xy = road.position(s, np.full_like(s, road.boundary_r(b)))
        ax.plot(xy[:, 0], xy[:, 1], color="0.5", lw=0.8)
    path = np.asarray(trace.path_xy)
    if len(path):
        ax.plot(path[:, 0], path[:, 1], "-", color=np.asarray(COLOURS[FUSED]) / 255, lw=1.5,
                label="driven path")
        ax.plot(*path[-1], "o", color="0.2", label="end")
    ax.set_aspect("equal")
    ax.set(xlabel="x (m)", ylabel="y (m)")
    ax.set_title(f"{title}\ntop view", fontsize=10)
    ax.legend(fontsize=8)
    save(fig, "top_view.png")
    return written
