"""Episode metrics: per detector, for the reference (the paper's "observer") and the fused output.

Definitions (all against ground truth from the road, never from images):
  - offset RMSE / max error (cm): the estimate's offset vs the true offset at the same
    look-ahead x_m, over the steps where the source had a valid estimate. A front model's is
    its raw detection (the detector as the paper's Tables 3-4 score it) at the detector's own
    look-ahead; "<model>:track" is that model's own Kalman track at the fused output's
    look-ahead, so that the fused output (by default the selected model's track) is compared
    like for like;
  - the lane behind ADE / FDE is the source's lane centre line: a raw detection's centre (one
    boundary shifted by the estimator's measured lane width), a model's track, the fused lane;
  - ADE / FDE (cm) of a tracked lane centre line: at each step, the lateral error
    |y_est(x) - y_true(x)| at look-ahead points x_1 < ... < x_N, default x = 4, 6, ..., 20 m
    (ADE_POINTS_M: the front detectors' ground window, detectors/config.py profiles.front, so no
    source is scored on extrapolation beyond what the cameras see). y_true is the road's exact
    lane centre at each x (`ground_truth.lane_centre_at`), not a polynomial fitted to it. ADE is
    the error's mean over the points and the steps, FDE its mean over the steps at the farthest
    point x_N = 20 m (the trajectory-forecasting convention, with distance ahead in place of
    time). A quadratic estimate cannot follow a tight arc exactly: on case2_sharp_turn's 40 m
    radius even the best quadratic over 4-20 m scores ADE ~0.9 cm, FDE ~2.4 cm;
  - valid share: the share of steps with a valid estimate (time with none is reported too);
  - fused vs track on common steps (`fused_vs_track`, per "<model>:track"): the RMSE of the
    fused output and of the model's track over the steps where both had an offset, their
    number and their share of the episode's steps. Each source's own RMSE is over its own
    valid steps: a track that abstains on the hard frames looks better than the output that
    had to answer there; on common steps the two are compared like for like;
  - the car's own lateral error: RMS and max of the true offset at x = 0;
  - lane departures: times a wheel's contact point crosses an ego-lane boundary (counted on
    entry, not per step);
  - MMAE switches: changes of the selected model;
  - safety among other vehicles (lanekeep/scoring/safety.py): `min_ttc_s`, the smallest time to
    collision with the vehicle ahead in the car's path (inf when the car never closed on one;
    JSON null), `min_gap_m`, the smallest bumper-to-bumper gap to it (None when there never
    was one; JSON null), `hard_braking_events` (decelerations of 0.4 g or more, one per
    braking) and `collisions` (contacts with another vehicle: 0 or 1, the episode ends there).

An episode ends with a status (STATUSES): "completed" (all its steps), "off_road" (the car left
the road: lanekeep/loop/episode.py; the step on which it left is scored, the ones it never drove are
not), "collision" (the car touched another vehicle; likewise its step is scored),
"interrupted" (Ctrl-C, SIGTERM) or "unstable" (the physics blew up). `criteria` holds the
pass/fail verdicts of lanekeep/scoring/criteria.py once a report has been judged.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.scoring.safety import SafetyTally, StepSafety

# Look-ahead points (m) of ADE / FDE: the front detectors' window, 4-20 m, every 2 m.
ADE_POINTS_M = (4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0)
STATUSES = ("completed", "off_road", "collision", "interrupted", "unstable")
# The ends of a drive that are failures of the car's: it left the road, hit a vehicle or its
# physics blew up. An interrupted run (Ctrl-C) is not the car's failure, only a shorter drive.
FAILED_STATUSES = ("off_road", "collision", "unstable")


def drive_failed(lane_departures: int, status: str) -> bool:
    """Whether a drive failed: a wheel crossed a lane boundary, or it ended in FAILED_STATUSES.

    Departures alone hide a drive that a collision ended before the car left its lane; two runs
    compared on departures alone would pair a 21 s crash with a 25 s drive that departs."""
    return lane_departures > 0 or status in FAILED_STATUSES


@dataclass(frozen=True)
class Verdict:
    """One pass/fail criterion of an episode: its limit, the episode's value and the outcome.
    `value` is None where the episode has none (a fused RMSE with no valid estimate: fails)."""

    name: str  # e.g. "lane_departures", "car_lateral_error_m", "status"
    limit: float | int | str
    value: float | int | str | None
    passed: bool

    def line(self) -> str:
        """"lane_departures  2  (must be <= 0)  FAIL": one row of the report's table."""
        value = "-" if self.value is None else (
            f"{self.value:.3f}" if isinstance(self.value, float) else str(self.value))
        limit = self.limit if isinstance(self.limit, str) else f"<= {self.limit:g}"
        return (f"{self.name:<20}{value:>10}  (must be {limit})  "
                f"{'ok' if self.passed else 'FAIL'}")


@dataclass(frozen=True)
class SourceReport:
    """Accuracy of one offset source over an episode (cm).

    `drift_cm` is paper 000's frame-to-frame drift: over consecutive steps where the source
    has an offset, the RMS of its change from the last step minus the true offset's change
    (the car's own motion is in both, so what is left is jitter and lag). NaN with fewer than
    two consecutive offsets."""

    rmse_cm: float
    max_cm: float
    ade_cm: float
    fde_cm: float
    valid_share: float
    drift_cm: float = math.nan
    # Pearson correlation over the steps where both had an offset of this source's error with
    # the rear reference's error (both against the truth at their own look-ahead): a reference
    # whose errors follow a model's cannot tell when that model is wrong. NaN for the reference
    # itself and with fewer than three such steps (or no spread).
    reference_error_corr: float = math.nan


@dataclass(frozen=True)
class CommonSteps:
    """The fused output against one model's own track over the steps where BOTH had an offset
    (cm): each source's own RMSE (SourceReport) is over its own valid steps, so a track that
    abstains on the hard frames looks better than the output that had to answer there, and
    "fused vs track" compared different steps. NaN RMSEs when no step is common."""

    rmse_a_cm: float  # a: the fused output
    rmse_b_cm: float  # b: the model's track
    steps: int  # the steps both had an offset
    share: float  # `steps` over the episode's scored steps


# The car's own outcome of an episode (EpisodeReport fields), beside its sources' metrics: the
# one list the seed summaries, the sweeps and the comparisons name.
EPISODE_METRICS = ("car_rms_cm", "car_max_cm", "lane_departures", "mmae_switches",
                   "reference_repairs", "no_estimate_s")
# The car's safety among other vehicles (EpisodeReport fields, lanekeep/scoring/safety.py).
# Apart from EPISODE_METRICS: reports written before them lack the keys, and the minima have
# no mean over seeds (inf / None when the car never had a vehicle ahead).
SAFETY_METRICS = ("min_ttc_s", "min_gap_m", "hard_braking_events", "collisions")


@dataclass(frozen=True)
class EpisodeReport:
    scenario: str
    seed: int
    duration_s: float
    steps: int
    sources: dict[str, SourceReport]
    car_rms_cm: float
    car_max_cm: float
    lane_departures: int
    mmae_switches: int
    no_estimate_s: float
    reference_repairs: int
    completed: bool = True
    wall_s: float = 0.0
    stop_reason: str = ""  # why an incomplete episode stopped ("" when completed)
    status: str = "completed"  # one of STATUSES; `completed` is status == "completed"
    # pass/fail verdicts (lanekeep/scoring/criteria.py), if judged
    criteria: tuple[Verdict, ...] = ()
    # (nearest, farthest) look-ahead (m) of ADE / FDE, for the table's footer.
    ade_range_m: tuple[float, float] = (ADE_POINTS_M[0], ADE_POINTS_M[-1])
    # The fused output against each model's track ("hough:track") on their common steps.
    fused_vs_track: dict[str, CommonSteps] = field(default_factory=dict)
    # Safety among other vehicles (SAFETY_METRICS; the module docstring): the smallest time to
    # collision with the vehicle ahead in the car's path (inf: never closing on one; JSON
    # null), the smallest gap to it (None: never one), hard braking events, collisions.
    min_ttc_s: float = math.inf
    min_gap_m: float | None = None
    hard_braking_events: int = 0
    collisions: int = 0

    def __post_init__(self) -> None:
        # A report read back from JSON carries a list; keep reports equal after a round trip.
        object.__setattr__(self, "ade_range_m", tuple(float(v) for v in self.ade_range_m))
        object.__setattr__(self, "criteria", tuple(
            v if isinstance(v, Verdict) else Verdict(**v) for v in self.criteria))
        if self.status == "completed" and not self.completed:  # a document from before `status`
            object.__setattr__(self, "status", "interrupted" if self.stop_reason in
                               ("", "interrupted") else "unstable")
        if self.min_ttc_s is None or math.isnan(self.min_ttc_s):  # JSON null: never closing
            object.__setattr__(self, "min_ttc_s", math.inf)
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {self.status!r}")
        if self.completed != (self.status == "completed"):
            raise ValueError(f"completed = {self.completed} contradicts status {self.status!r}")

    def safety_line(self) -> str:
        """"safety: min TTC 3.1 s, min gap 12.4 m (vehicle ahead in the car's path); hard
        braking 0 (>= 0.4 g); collisions 0": the table's line below the car's."""
        if self.min_gap_m is None:
            ahead = "no vehicle ahead in the car's path"
        else:
            ttc = (f"{self.min_ttc_s:.1f} s" if math.isfinite(self.min_ttc_s)
                   else "- (never closing)")
            ahead = (f"min TTC {ttc}, min gap {self.min_gap_m:.1f} m (vehicle ahead in the "
                     "car's path)")
        return (f"safety: {ahead}; hard braking {self.hard_braking_events} (>= 0.4 g); "
                f"collisions {self.collisions}")

    @property
    def passed(self) -> bool:
        """Every criterion met (True for a report not judged: no criteria)."""
        return all(v.passed for v in self.criteria)

    @property
    def failed(self) -> bool:
        """The drive failed (drive_failed): a lane departure, or off the road, a collision or
        unstable physics."""
        return drive_failed(self.lane_departures, self.status)

    def failed_criteria(self) -> list[Verdict]:
        return [v for v in self.criteria if not v.passed]

    def to_dict(self) -> dict:
        return asdict(self)

    def table(self) -> str:
        """The paper's Table 3-4 layout: columns = sources, rows = metrics (cm)."""
        names = list(self.sources)
        width = max(10, *(len(n) for n in names))
        rows = [("RMSE", "rmse_cm"), ("max error", "max_cm"), ("ADE", "ade_cm"),
                ("FDE", "fde_cm"), ("drift", "drift_cm"), ("valid %", "valid_share")]
        lines = [f"{'(cm)':<10}" + "".join(f"{n:>{width + 2}}" for n in names)]
        for label, key in rows:
            cells = []
            for n in names:
                value = getattr(self.sources[n], key)
                value = value * 100.0 if key == "valid_share" else value
                cells.append(f"{'-' if math.isnan(value) else f'{value:.2f}':>{width + 2}}")
            lines.append(f"{label:<10}" + "".join(cells))
        lines.append(
            f"car: lateral RMS {self.car_rms_cm:.1f} cm, max {self.car_max_cm:.1f} cm; "
            f"lane departures {self.lane_departures}; MMAE switches {self.mmae_switches}; "
            f"reference repairs {self.reference_repairs}; no estimate {self.no_estimate_s:.1f} s"
            + ("" if self.completed else f"  [STOPPED ({self.status.replace('_', ' ')}): "
               f"partial episode: {self.stop_reason or self.status}]")
        )
        lines.append(self.safety_line())
        near, far = self.ade_range_m
        lines.append(f"ADE/FDE: lane centre vs exact road geometry at x = {near:g}-{far:g} m "
                     f"ahead; FDE at {far:g} m; drift: RMS of the offset's change between "
                     "frames minus the true change")
        if self.criteria:
            lines.append(f"criteria: {'PASS' if self.passed else 'FAIL'}")
            lines.extend("  " + v.line() for v in self.criteria)
        return "\n".join(lines)


@dataclass
class _ErrorSums:
    """Running sums of a signed error (m): what RMSE and max need, in constant memory, so an
    hour-long episode (tools/soak) does not hold every step's value."""

    count: int = 0
    sum_sq: float = 0.0
    max_abs: float = 0.0

    def add(self, error_m: float) -> None:
        self.count += 1
        self.sum_sq += error_m * error_m
        self.max_abs = max(self.max_abs, abs(error_m))

    def rms_cm(self) -> float:
        return math.sqrt(self.sum_sq / self.count) * 100 if self.count else math.nan

    def max_cm(self) -> float:
        return self.max_abs * 100 if self.count else math.nan


@dataclass
class _PairSums:
    """Running sums for a Pearson correlation of two errors, in constant memory."""

    n: int = 0
    sx: float = 0.0
    sy: float = 0.0
    sxx: float = 0.0
    syy: float = 0.0
    sxy: float = 0.0

    def add(self, x: float, y: float) -> None:
        self.n += 1
        self.sx += x
        self.sy += y
        self.sxx += x * x
        self.syy += y * y
        self.sxy += x * y

    def corr(self) -> float:
        if self.n < 3:
            return math.nan
        vx = self.sxx - self.sx * self.sx / self.n
        vy = self.syy - self.sy * self.sy / self.n
        floor = self.n * 1e-12  # errors in metres: a spread under a micrometre is none
        if vx <= floor or vy <= floor:
            return math.nan
        return (self.sxy - self.sx * self.sy / self.n) / math.sqrt(vx * vy)


@dataclass
class _CommonAccumulator:
    """Both sources' errors over the steps where both had one."""

    a: _ErrorSums = field(default_factory=_ErrorSums)
    b: _ErrorSums = field(default_factory=_ErrorSums)

    def add(self, error_a_m: float, error_b_m: float) -> None:
        self.a.add(error_a_m)
        self.b.add(error_b_m)


@dataclass
class _SourceAccumulator:
    offsets: _ErrorSums = field(default_factory=_ErrorSums)
    drift: _ErrorSums = field(default_factory=_ErrorSums)
    last: tuple[float, float] | None = None  # (estimate, truth) of the previous step, if valid
    lanes: int = 0               # steps with a lane centre line
    lateral_sum_m: float = 0.0   # sum over those steps of the mean error over the ADE points
    final_sum_m: float = 0.0     # sum over those steps of the error at the last ADE point
    valid: int = 0
    steps: int = 0
    with_reference: _PairSums = field(default_factory=_PairSums)


class Metrics:
    """Accumulates per-step errors; `report()` summarises them."""

    def __init__(self, source_names: list[str], ade_points_m: tuple[float, ...] = ADE_POINTS_M,
                 fused: str | None = None, tracks: tuple[str, ...] = ()) -> None:
        """`fused` and `tracks`: the sources the report's `fused_vs_track` compares on their
        common steps (lanekeep/scoring/step_score.py names them)."""
        self.ade_points_m = np.asarray(ade_points_m, dtype=float)
        if self.ade_points_m.ndim != 1 or not np.all(np.diff(self.ade_points_m) > 0):
            raise ValueError(f"ade_points_m must increase (FDE is at the last), got {ade_points_m}")
        self._sources = {name: _SourceAccumulator() for name in source_names}
        self._car = _ErrorSums()
        self._departed = False
        self.lane_departures = 0
        self.mmae_switches = 0
        self.reference_repairs = 0
        self._no_estimate_steps = 0
        self._last_selected: int | None = None
        self._step_errors: dict[str, float] = {}  # this step's error (m) per valid source
        unknown = [n for n in (fused, *tracks) if n is not None and n not in self._sources]
        if unknown or (tracks and fused is None):
            raise ValueError(f"fused_vs_track needs a fused source and tracks among the "
                             f"sources, got fused={fused!r}, tracks={tracks}")
        self._fused = fused
        self._common = {track: _CommonAccumulator() for track in tracks}
        self.safety = SafetyTally()

    def add_offset(self, name: str, estimate_m: float | None, truth_m: float) -> None:
        acc = self._sources[name]
        acc.steps += 1
        if estimate_m is not None and math.isfinite(estimate_m):
            acc.valid += 1
            acc.offsets.add(estimate_m - truth_m)
            self._step_errors[name] = estimate_m - truth_m
            if acc.last is not None:
                acc.drift.add((estimate_m - acc.last[0]) - (truth_m - acc.last[1]))
            acc.last = (estimate_m, truth_m)
        else:
            acc.last = None

    def pair_with_reference(self, reference: str) -> None:
        """End of a step's offsets: pair each source's error with `reference`'s (when both
        had one) for `reference_error_corr`, and the fused output's with each track's for
        `fused_vs_track`, then forget the step's errors."""
        ref = self._step_errors.get(reference)
        if ref is not None:
            for name, error in self._step_errors.items():
                if name != reference:
                    self._sources[name].with_reference.add(error, ref)
        fused = self._step_errors.get(self._fused) if self._fused is not None else None
        if fused is not None:
            for track, common in self._common.items():
                if track in self._step_errors:
                    common.add(fused, self._step_errors[track])
        self._step_errors.clear()

    def add_lane(self, name: str, centre: np.ndarray | None, truth_y: np.ndarray) -> None:
        """Lateral errors of lane centre `centre` ([c0, c1, c2]; None = no lane this step)
        against the true centre's y (m) at `self.ade_points_m` (`ground_truth.lane_centre_at`)."""
        truth_y = np.asarray(truth_y, dtype=float)
        if truth_y.shape != self.ade_points_m.shape:
            raise ValueError(f"truth_y must hold y at the {len(self.ade_points_m)} ADE points, "
                             f"got shape {truth_y.shape}")
        if centre is None:
            return
        error = np.abs(LanePoly.of(centre).y(self.ade_points_m) - truth_y)
        acc = self._sources[name]
        acc.lanes += 1
        acc.lateral_sum_m += float(error.mean())
        acc.final_sum_m += float(error[-1])

    def add_car(self, true_offset_m: float, wheels_outside_lane: bool) -> None:
        self._car.add(true_offset_m)
        if wheels_outside_lane and not self._departed:
            self.lane_departures += 1
        self._departed = wheels_outside_lane

    def add_selection(self, selected: int, reference_repaired: bool) -> None:
        if self._last_selected is not None and selected != self._last_selected:
            self.mmae_switches += 1
        self._last_selected = selected
        self.reference_repairs += int(reference_repaired)

    def add_safety(self, step: StepSafety) -> None:
        """A step's gap, TTC, contact and the car's acceleration (lanekeep/scoring/safety.py)."""
        self.safety.add(step)

    def add_no_estimate(self) -> None:
        self._no_estimate_steps += 1

    def report(self, scenario: str, seed: int, dt_s: float, completed: bool = True,
               wall_s: float = 0.0, stop_reason: str = "", status: str | None = None
               ) -> EpisodeReport:
        """The report so far; `status` defaults to "completed" / "interrupted" by `completed`."""
        sources = {}
        for name, acc in self._sources.items():
            sources[name] = SourceReport(
                rmse_cm=acc.offsets.rms_cm(),
                max_cm=acc.offsets.max_cm(),
                ade_cm=acc.lateral_sum_m / acc.lanes * 100 if acc.lanes else math.nan,
                fde_cm=acc.final_sum_m / acc.lanes * 100 if acc.lanes else math.nan,
                valid_share=acc.valid / acc.steps if acc.steps else 0.0,
                drift_cm=acc.drift.rms_cm(),
                reference_error_corr=acc.with_reference.corr(),
            )
        car = self._car
        steps = self._sources[self._fused].steps if self._fused is not None else 0
        fused_vs_track = {
            track: CommonSteps(rmse_a_cm=common.a.rms_cm(), rmse_b_cm=common.b.rms_cm(),
                               steps=common.a.count,
                               share=common.a.count / steps if steps else 0.0)
            for track, common in self._common.items()}
        return EpisodeReport(
            scenario=scenario,
            seed=seed,
            duration_s=car.count * dt_s,
            steps=car.count,
            sources=sources,
            car_rms_cm=car.rms_cm(),
            car_max_cm=car.max_cm(),
            lane_departures=self.lane_departures,
            mmae_switches=self.mmae_switches,
            no_estimate_s=self._no_estimate_steps * dt_s,
            reference_repairs=self.reference_repairs,
            completed=completed,
            wall_s=wall_s,
            stop_reason=stop_reason,
            status=status or ("completed" if completed else "interrupted"),
            ade_range_m=(float(self.ade_points_m[0]), float(self.ade_points_m[-1])),
            fused_vs_track=fused_vs_track,
            min_ttc_s=self.safety.min_ttc_s,
            min_gap_m=self.safety.min_gap_m,
            hard_braking_events=self.safety.hard_braking_events,
            collisions=self.safety.collisions,
        )
