"""Multiple-model adaptive estimation over lane detectors (paper 001 §2.3 eq. 1-8, §3).

N front models (detector + `LaneTracker` each) are weighed against the rear-camera reference
offset. Per control step the episode calls::

    out = mmae.step(reference_offset_m,                 # rear reference, None if missed
                    [t.offset_m(x) for t in trackers],  # None for an invalid track
                    [t.offset_variance_m2(x) or nan for t in trackers],  # C P C' of eq. 8
                    s_m=travelled_distance_m)           # needed in "distance_aligned" mode only
    steer_on = out.selected_offset_m  # paper's rule (argmax); or out.fused_offset_m

Residuals (`MMAEConfig.residual_mode`):

* ``"one_step_delay"``, eq. 2: r_n = z_ref(k) - z_n(k-1), the paper's mode; the rear camera sees
  road the front models saw before, and the paper takes that as one step.
* ``"distance_aligned"``: the reference at travelled distance s looks `reference_lag_m` behind
  where the front models look, so each model's offset is interpolated from its history at
  s - reference_lag_m and compared with the reference.
* ``"same_step"``: r_n = z_ref(k) - z_n(k), for offsets the caller has already brought to
  where the reference looks (the closed loop's odometry alignment, estimators/alignment.py).

Choices the paper leaves open:

* a missed (None or non-finite) reference leaves the probabilities unchanged;
* a model with no offset to compare (missing now, or missing in its history) gets the log-density
  of the least likely compared model minus `missing_model_log_penalty`: it loses probability
  against every model that could be checked, yet the floor lets it recover once it reports again;
  when no model can be compared the probabilities are unchanged;
* the floor is exact: after each update every probability is in [floor, 1] and they sum to 1.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lanekeep.estimators.reference import ReferenceRepair

RESIDUAL_MODES = ("one_step_delay", "distance_aligned", "same_step")
LOG_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class MMAEConfig:
    """Settings of the MMAE selector; defaults are for 0.1 s steps and camera-grade offsets."""

    residual_mode: str = "one_step_delay"
    reference_std_m: float = 0.05  # R of eq. 8: the rear reference's offset noise
    probability_floor: float = 1e-3  # every model keeps this much, so a failed one can recover
    jump_threshold_m: float = 0.20  # §3: a larger reference change is a reference failure
    max_repair_steps: int = 5  # then a standing change is accepted (e.g. a lane change)
    missing_model_log_penalty: float = 5.0  # e^5 ~ 150x less likely than the worst compared model
    reference_lag_m: float = 0.0  # distance_aligned: front look point minus rear look point
    history_steps: int = 200  # distance_aligned: model offsets kept, one per step

    def __post_init__(self) -> None:
        if self.residual_mode not in RESIDUAL_MODES:
            raise ValueError(
                f"residual_mode must be one of {RESIDUAL_MODES}, got {self.residual_mode!r}"
            )
        if not (np.isfinite(self.reference_std_m) and self.reference_std_m > 0):
            raise ValueError(f"reference_std_m must be positive, got {self.reference_std_m}")
        if not 0.0 <= self.probability_floor < 1.0:
            raise ValueError(f"probability_floor must be in [0, 1), got {self.probability_floor}")
        if not self.missing_model_log_penalty >= 0:
            raise ValueError("missing_model_log_penalty must be >= 0")
        if not (np.isfinite(self.reference_lag_m) and self.reference_lag_m >= 0):
            raise ValueError(f"reference_lag_m must be >= 0, got {self.reference_lag_m}")
        if self.history_steps < 2:
            raise ValueError(f"history_steps must be >= 2, got {self.history_steps}")


@dataclass(frozen=True)
class MMAEOutput:
    """One step of the selector. Offsets are None when no model has a current offset."""

    probabilities: np.ndarray  # (n,), each in [floor, 1], sum 1
    selected: int  # argmax of the probabilities among models with a current offset
    selected_offset_m: float | None
    fused_offset_m: float | None  # probability-weighted over models with a current offset
    reference_m: float | None  # after repair; None when missed
    reference_repaired: bool  # the reference jumped by more than the threshold (§3)
    residuals_m: np.ndarray  # (n,) r_n of eq. 2, NaN where not compared
    updated: bool  # whether eq. 4 ran this step


def apply_probability_floor(p: np.ndarray, floor: float) -> np.ndarray:
    """Raise probabilities below `floor` to it and rescale the others so the sum stays 1.

    Rescaling can push another model under the floor, so repeat until none is (at most n passes).
    """
    p = np.asarray(p, dtype=float) / np.sum(p)
    fixed = np.zeros(p.shape, dtype=bool)
    out = p.copy()
    for _ in range(len(p)):
        free = ~fixed
        out[free] = p[free] / p[free].sum() * (1.0 - floor * fixed.sum())
        below = free & (out < floor)
        if not below.any():
            break
        fixed |= below
    out[fixed] = floor
    return out


def log_density(residual_m: np.ndarray, psi_m2: np.ndarray) -> np.ndarray:
    """Log of the scalar Gaussian density of eq. 5-7 (measurement dimension l = 1).

    Paper 001's eq. 7 reads o = +1/2 r' Psi^-1 r; the density is exp(-1/2 r' Psi^-1 r), as in
    its source (Rahman et al., 2017). We use the minus sign.
    """
    log_beta = -0.5 * (LOG_2PI + np.log(psi_m2))  # eq. 6: beta = 1 / ((2 pi)^(l/2) |Psi|^(1/2))
    o = -0.5 * residual_m**2 / psi_m2  # eq. 7, with the sign corrected
    return log_beta + o  # eq. 5: log f = log beta + o


class MMAE:
    """Model probabilities of N front models against the rear reference (paper 001 eq. 2-8)."""

    def __init__(self, n_models: int, config: MMAEConfig | None = None,
                 prior: Sequence[float] | None = None) -> None:
        """`prior`: the probabilities before any reference is seen (None: equal, the
        paper's); positive, normalised here."""
        self.config = config if config is not None else MMAEConfig()
        if n_models < 1:
            raise ValueError(f"n_models must be >= 1, got {n_models}")
        if self.config.probability_floor * n_models >= 1.0:
            raise ValueError("probability_floor * n_models must be < 1")
        self.n_models = n_models
        if prior is None:
            prior = np.ones(n_models)
        prior = np.asarray(prior, dtype=float)
        if prior.shape != (n_models,) or not np.all(np.isfinite(prior) & (prior > 0)):
            raise ValueError(f"prior must be {n_models} positive numbers, got {prior}")
        self._prior = apply_probability_floor(prior, self.config.probability_floor)
        self._repair = ReferenceRepair(self.config.jump_threshold_m, self.config.max_repair_steps)
        self.reset()

    def reset(self) -> None:
        """The prior probabilities, no history."""
        self._p = self._prior.copy()
        self._previous: tuple[np.ndarray, np.ndarray] | None = None  # one_step_delay: z, var
        self._history: deque[tuple[float, np.ndarray, np.ndarray]] = deque(
            maxlen=self.config.history_steps
        )  # distance_aligned: (s, z, var)
        self._repair.reset()

    @property
    def probabilities(self) -> np.ndarray:
        return self._p.copy()

    def step(
        self,
        reference_offset_m: float | None,
        model_offsets_m: Sequence[float | None],
        model_variances_m2: Sequence[float | None],
        s_m: float | None = None,
    ) -> MMAEOutput:
        """Update the model probabilities with this step's reference and model offsets.

        Args:
            reference_offset_m: rear-camera reference offset (m); None or NaN when missed.
            model_offsets_m: each front model's current offset (m); None or NaN when missing.
            model_variances_m2: each model's offset variance C P C' (m^2), eq. 8's model term.
            s_m: travelled distance of the car (m); required in "distance_aligned" mode.
        """
        z, var = self._validate(model_offsets_m, model_variances_m2)
        reference_m, repaired = self._repair(reference_offset_m)
        compared = self._compared_offsets(z, var, s_m)  # z_n(k-1) of eq. 2, or aligned
        residuals = np.full(self.n_models, np.nan)
        updated = False
        if reference_m is not None and compared is not None:
            z_cmp, var_cmp = compared
            residuals = reference_m - z_cmp  # eq. 2: r_n = z_ref(k) - z_n(k-1)
            present = np.isfinite(residuals)
            if present.any():
                self._update(residuals, var_cmp, present)
                updated = True
        return self._output(z, reference_m, repaired, residuals, updated)

    def _update(self, residuals: np.ndarray, var_cmp: np.ndarray, present: np.ndarray) -> None:
        cfg = self.config
        psi = var_cmp[present] + cfg.reference_std_m**2  # eq. 8: Psi = C P C' + R
        log_f = np.empty(self.n_models)
        log_f[present] = log_density(residuals[present], psi)  # eq. 5-7
        log_f[~present] = log_f[present].min() - cfg.missing_model_log_penalty
        log_num = log_f + np.log(self._p)  # eq. 4 numerator: f_n p_n(k-1), in logs
        log_den = np.logaddexp.reduce(log_num)  # eq. 4 denominator: sum_j f_j p_j(k-1)
        self._p = apply_probability_floor(np.exp(log_num - log_den), cfg.probability_floor)

    def _compared_offsets(
        self, z: np.ndarray, var: np.ndarray, s_m: float | None
    ) -> tuple[np.ndarray, np.ndarray] | None:
        if self.config.residual_mode == "one_step_delay":
            previous, self._previous = self._previous, (z, var)
            return previous
        if self.config.residual_mode == "same_step":
            return z, var
        if s_m is None or not np.isfinite(s_m):
            raise ValueError("distance_aligned mode needs a finite travelled distance s_m")
        if self._history and s_m < self._history[-1][0]:
            raise ValueError(f"s_m must not decrease: {s_m} < {self._history[-1][0]}")
        if self._history and s_m == self._history[-1][0]:
            self._history.pop()  # standing still: keep the newest estimate for this position
        self._history.append((float(s_m), z, var))
        return self._aligned(s_m - self.config.reference_lag_m)

    def _aligned(self, s_ref: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Each model's offset and variance interpolated at road position s_ref, NaN if missing."""
        s = np.array([h[0] for h in self._history])
        if s_ref < s[0] or s_ref > s[-1]:
            return None
        i = int(np.searchsorted(s, s_ref, side="left"))
        if s[i] == s_ref:
            return self._history[i][1], self._history[i][2]
        (s0, z0, v0), (s1, z1, v1) = self._history[i - 1], self._history[i]
        w = (s_ref - s0) / (s1 - s0)
        return (1.0 - w) * z0 + w * z1, (1.0 - w) * v0 + w * v1  # NaN stays NaN

    def _validate(
        self, offsets: Sequence[float | None], variances: Sequence[float | None]
    ) -> tuple[np.ndarray, np.ndarray]:
        if len(offsets) != self.n_models or len(variances) != self.n_models:
            raise ValueError(
                f"expected {self.n_models} offsets and variances, "
                f"got {len(offsets)} and {len(variances)}"
            )
        z = np.array([np.nan if o is None else o for o in offsets], dtype=float)
        var = np.array([np.nan if v is None else v for v in variances], dtype=float)
        if np.any(var < 0):
            raise ValueError(f"model variances must be >= 0, got {var}")
        bad = ~(np.isfinite(z) & np.isfinite(var))
        z[bad] = np.nan  # a model without a usable offset or variance is missing this step
        var[bad] = np.nan
        return z, var

    def _output(
        self,
        z: np.ndarray,
        reference_m: float | None,
        repaired: bool,
        residuals: np.ndarray,
        updated: bool,
    ) -> MMAEOutput:
        valid = np.isfinite(z)
        if valid.any():
            selected = int(np.argmax(np.where(valid, self._p, -np.inf)))  # paper's decision rule
            selected_offset = float(z[selected])
            w = self._p[valid]
            fused = float(np.sum(w * z[valid]) / np.sum(w))
        else:
            selected, selected_offset, fused = int(np.argmax(self._p)), None, None
        return MMAEOutput(
            probabilities=self._p.copy(),
            selected=selected,
            selected_offset_m=selected_offset,
            fused_offset_m=fused,
            reference_m=reference_m,
            reference_repaired=repaired,
            residuals_m=residuals,
            updated=updated,
        )
