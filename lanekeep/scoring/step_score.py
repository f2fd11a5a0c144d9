"""Scoring one step's estimates against its truth: per front model its raw detection (at the
detector's own look-ahead) and its own Kalman track (at the output's look-ahead, like the
fused output), the reference, and the fused output. Like for like: a track is compared with
the fused output, both at the same look-ahead."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.driver.driver import REFERENCE
from lanekeep.estimators.lane_estimator import EstimatorOutput
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.scoring.metrics import Metrics
from lanekeep.scoring.step_truth import StepTruth

FUSED = "fused"
TRACK_SUFFIX = ":track"  # a front model's own Kalman track, scored like the fused output


def track_source(model: str) -> str:
    """The report column of a model's own track ("hough" -> "hough:track")."""
    return model + TRACK_SUFFIX


def source_names(models: list[str]) -> list[str]:
    """Report columns in order: per model its raw detection and its own track, then the
    fused output and the reference."""
    return [n for m in models for n in (m, track_source(m))] + [FUSED, REFERENCE]


def loop_metrics(models: list[str]) -> Metrics:
    """The metrics of a loop with front models `models`: its columns (`source_names`), and the
    fused output against each model's track on their common steps (`fused_vs_track`)."""
    return Metrics(source_names(models), fused=FUSED,
                   tracks=tuple(track_source(m) for m in models))


def score_estimates(metrics: Metrics, models: list[str], estimates: Mapping[str, LaneEstimate],
                    estimate: EstimatorOutput, truth: StepTruth,
                    centre_of: Callable[[LaneEstimate], np.ndarray | None]
                    ) -> dict[str, float | None]:
    """Add the step's offsets and lanes to `metrics`; returns each model's track offset at
    the output's look-ahead (None while it has no track). `centre_of` turns a detection into
    the centre line the estimator would track (its lane-width centring)."""
    x_out = estimate.offset_x_m
    track_offsets: dict[str, float | None] = {}
    for name in models:
        e = estimates[name]
        metrics.add_offset(name, e.offset_m if e.valid else None, truth.offset_at(e.x_m))
        metrics.add_lane(name, centre_of(e), truth.centre_at_ade_m)
        track = estimate.tracked[name]
        track_offsets[name] = None if track is None else float(LanePoly.of(track).offset_m(x_out))
        metrics.add_offset(track_source(name), track_offsets[name], truth.offset_at(x_out))
        metrics.add_lane(track_source(name), track, truth.centre_at_ade_m)
    ref = estimates[REFERENCE]
    metrics.add_offset(REFERENCE, estimate.selection.reference_m if ref.valid else None,
                       truth.offset_at(estimate.reference_x_m))
    metrics.add_offset(FUSED, estimate.offset_m, truth.offset_at(x_out))
    metrics.add_lane(FUSED, estimate.centre, truth.centre_at_ade_m)
    metrics.pair_with_reference(REFERENCE)
    if estimate.centre is None:
        metrics.add_no_estimate()
    return track_offsets
