"""MOBIL ("minimizing overall braking induced by lane changes"): whether a driver changes lane,
judged from car-following accelerations before and after the change.

Kesting, Treiber and Helbing (2007), "General lane-changing model MOBIL for car-following
models", Transportation Research Record 1999, 86-94. Three drivers are affected: c, the one
who changes; n, its new follower in the target lane; o, its old follower in the lane it leaves.
a is an acceleration as things are, ã (here `*_after`) one if c has changed. The change happens
when it is safe for n and worth it overall:

    safety:     ã_n >= -b_safe
    incentive:  ã_c - a_c + p [(ã_n - a_n) + (ã_o - a_o)] > Δa_th        (symmetric rules)

p, the politeness, weighs the others' gain or loss against c's own; Δa_th keeps it from
changing for a marginal gain. Under asymmetric (European, keep-right) rules, with a bias
Δa_bias > 0 towards the right lane, the paper's variant counts only the follower whose lane
has priority and shifts the threshold by the bias:

    to the right:  ã_c - a_c + p (ã_o - a_o) + Δa_bias > Δa_th
    to the left:   ã_c - a_c + p (ã_n - a_n) - Δa_bias > Δa_th

(the paper's further rule that nobody passes on the right, a cap on the right lane's
acceleration, is not modelled). The accelerations come from any car-following model; the
flow (lanekeep/traffic/flow.py) uses the IDM (lanekeep/traffic/idm.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class MobilParams:
    """One driver's lane-change parameters. The paper's typical values: p in 0-0.5 (0 selfish,
    > 1 altruistic), Δa_th = 0.1 m/s^2, b_safe = 4 m/s^2 (well below the ~9 m/s^2 a car can
    brake), Δa_bias = 0.3 m/s^2 under European rules."""

    politeness: float = 0.3  # p: the weight of the followers' gain against its own (>= 0)
    threshold_mps2: float = 0.1  # Δa_th: the least overall gain worth a change
    safe_decel_mps2: float = 4.0  # b_safe: the hardest braking it may impose on its new follower
    # Δa_bias: 0 = symmetric rules (either lane may be used to pass); > 0 = keep right (the
    # asymmetric criteria above, biased by this much towards the right lane).
    keep_right_bias_mps2: float = 0.0

    def __post_init__(self):
        for name in ("politeness", "threshold_mps2", "safe_decel_mps2", "keep_right_bias_mps2"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"MobilParams.{name} must be finite and >= 0, got {value}")
        if self.safe_decel_mps2 == 0.0:
            raise ValueError("MobilParams.safe_decel_mps2 must be > 0, got 0")


def safety_ok(p: MobilParams, new_follower_accel_after: float) -> bool:
    """The safety criterion: the new follower would not have to brake harder than b_safe."""
    return new_follower_accel_after >= -p.safe_decel_mps2


def incentive(p: MobilParams, own_before: float, own_after: float,
              new_follower_before: float, new_follower_after: float,
              old_follower_before: float, old_follower_after: float,
              to_right: bool | None = None) -> float:
    """The overall gain (m/s^2) of the change, to compare with Δa_th. `to_right`: the change's
    side, read only under keep-right rules (bias > 0); None there counts as symmetric."""
    own = own_after - own_before
    new = new_follower_after - new_follower_before
    old = old_follower_after - old_follower_before
    bias = p.keep_right_bias_mps2
    if bias == 0.0 or to_right is None:
        return own + p.politeness * (new + old)
    if to_right:
        return own + p.politeness * old + bias
    return own + p.politeness * new - bias


def wants_change(p: MobilParams, own_before: float, own_after: float,
                 new_follower_before: float, new_follower_after: float,
                 old_follower_before: float, old_follower_after: float,
                 to_right: bool | None = None) -> bool:
    """MOBIL's decision: safe for the new follower and worth more than Δa_th."""
    if not safety_ok(p, new_follower_after):
        return False
    gain = incentive(p, own_before, own_after, new_follower_before, new_follower_after,
                     old_follower_before, old_follower_after, to_right)
    return gain > p.threshold_mps2
