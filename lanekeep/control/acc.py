"""Adaptive cruise control (ACC): the car's throttle and brake from its own forward radar and its
own signals (wheel-speed odometry, gyro), never the simulator's truth. The lateral loop is not
touched; with ACC off (`[control] acc = false`, the default) the controllers keep their plain
speed PI (lanekeep/control/pid.py `SpeedController`) exactly as before.

Each control period:
  1. Path: the car's path predicted as a circular arc of curvature yaw rate / speed (gyro and
     odometry; below MIN_PATH_SPEED_MPS the speed is floored, the ratio being noise there),
     low-passed with PATH_TIME_CONSTANT_S: a lane-keeping correction that yaws the car for a
     few tenths of a second is not the road's curve, and unfiltered it swings the arc's end
     50 m ahead by metres, from the lead onto the next lane's cars. The gyro's bias (drawn
     per episode, 0.3 deg/s 1-sigma) moves the arc by bias / v * x^2 / 2: 0.4 m at 50 m and
     15 m/s, inside the corridor's margin.
  2. Target: the nearest radar detection within `corridor_half_width_m` of that arc (1.2 m:
     production ACCs take objects within 1-1.2 m of the predicted path, littleprojects/ACC_W211
     requirements.md; a car in the next lane, 3.5 m over, stays out with 2.3 m to spare for
     prediction error, while a car cutting in counts once its centre is a third of a lane
     inside ours). Trees, poles and guard rails beside a bend and the cars in the other lanes
     lie farther off the arc and never count. The target followed last period is kept within
     HOLD_FACTOR times the corridor (hysteresis: it does not flicker out while the arc
     swings). A detection's speed along the car's heading is v + range_rate / cos(azimuth).
     Oncoming objects (that speed below -STATIONARY_MPS) are never targets. Standing objects
     (|speed| < STATIONARY_MPS) are targets only as the continuation of last period's target (a
     lead that stopped). The others are a radar's standing clutter as often as not: where a
     bend begins, the arc still runs straight for a second while the guard rail on the bend's
     outside crosses it some 20 m ahead (a time to collision of 1.3 s at 15 m/s in the 40 m
     radius bend of `sharp_turn`), and a radar cannot tell that rail from a stopped car. So,
     as radar-only ACC and AEB systems do, they are ignored: a car standing in the lane that
     the radar never saw move is not braked for (telling it from the rail needs the camera,
     or the lanes ahead for the path: not done here).
  3. Acceleration: the ACC model of Kesting, Treiber, Schönhof and Helbing ("Adaptive cruise
     control design for active congestion avoidance", Transp. Res. C 16, 2008; Treiber and
     Kesting, Traffic Flow Dynamics, 2013, sec. 11.3.7): the IDM (lanekeep/traffic/idm.py)
     blended with the constant-acceleration heuristic (CAH, `acc_model_acceleration`), which
     keeps the IDM from over-braking when a car cuts in close but not much slower: the IDM
     alone reads a 6 m gap against its desired 31 m as an emergency and would slow the car
     from 15 m/s to 6 behind a 12 m/s lead. The set speed is the scenario's target speed; a
     free road gives the IDM's free-road term, so the car cruises to it as before. The result
     is held in the ACC envelope of ISO 15622 / ISO 22179 (`envelope`), and its change per
     period in that envelope's jerk limit: a cut-in that needs it gets the envelope's full
     deceleration within about a second.
  4. Emergency (AEB-like): when the target closes with a time to collision below
     `emergency_ttc_s` (1.5 s; production AEB systems brake fully at a TTC of roughly 1-1.5 s
     after a warning at 2-3 s: an order of magnitude, not a standard's figure), the command is
     full braking, beyond the envelope, until it clears.
  5. Throttle: the commanded acceleration is integrated into a speed reference that the
     existing speed PI tracks (`SpeedController`, its gains unchanged): the ACC plans the
     speed, the PI holds it. The reference stays within REFERENCE_LEAD_MPS of the measured
     speed (no wind-up while the car cannot follow) and within [0, set speed]. Why this and not
     a throttle map: the car's throttle-to-acceleration gain G differs by ~5x between drive
     (~3 m/s^2 per unit) and brake (~0.9 * v m/s^2 per unit, ~14 at 15 m/s); a PI on speed
     tracks a ramp without steady error whatever G, its integrator holding what the ramp and
     the drag need. The speed loop's poles (s^2 + G kp s + G ki = 0: about -1.5 and -0.3 1/s
     in drive, -8 and -0.3 in brake) are real, so it does not overshoot, and faster than the
     car-following loop the ACC closes through the gap (time gap 1.8 s): the cascade is
     stable. In an emergency the throttle is -1 directly, and the reference restarts from the
     measured speed afterwards.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from lanekeep.control.pid import SpeedController
from lanekeep.core.signals import RadarReading, VehicleSignals
from lanekeep.traffic.idm import MAX_DECEL_MPS2, IdmParams, idm_acceleration

if TYPE_CHECKING:
    from lanekeep.scenario.schema import ControlConfig

# The ACC envelope of ISO 22179:2009 (full speed range ACC), which at high speed is ISO
# 15622:2018's (acceleration 2 m/s^2, deceleration 3.5 m/s^2, jerk 2.5 m/s^3): limits above
# V_HIGH and below V_LOW, linear in between (as summarised in littleprojects/ACC_W211,
# requirements.md, "Functional Limits").
V_LOW_MPS, V_HIGH_MPS = 5.0, 20.0
ACCEL_MAX_MPS2 = (4.0, 2.0)  # at V_LOW, at V_HIGH
DECEL_MAX_MPS2 = (5.0, 3.5)
JERK_MAX_MPS3 = (5.0, 2.5)
AEB_DECEL_MPS2 = MAX_DECEL_MPS2  # what full braking asks for: about 0.9 g, dry asphalt's limit
CAH_COOLNESS = 0.99  # Kesting et al. (2008): c, the weight of the CAH in a close situation
MIN_PATH_SPEED_MPS = 5.0
PATH_TIME_CONSTANT_S = 1.0
HOLD_FACTOR = 1.5
STATIONARY_MPS = 1.0  # odometry scale error (1 %) and Doppler noise stay well below it
REFERENCE_LEAD_MPS = 2.0
ASSOCIATION_GATE_M = 2.0  # a detection continues last period's target within this


@dataclass(frozen=True)
class AccSettings:
    """The ACC's settings: the scenario's `[control]` acc_* keys and the IDM's comfort figures.

    time_gap_s 1.8: the "half the speedometer" rule (metres = km/h / 2 is 1.8 s), inside the
    1.5-2.2 s span in which ISO 15622 asks ACCs to offer a setting. min_gap_m 4: the gap at
    standstill, within the 2-5 m stopping distance of ISO 22179 (full speed range ACC).
    comfort_accel_mps2 1.5 and comfort_decel_mps2 2.0 are the IDM's a and b: a little firmer
    than Treiber and Kesting's highway drivers (1.0 and 1.5, Traffic Flow Dynamics, Table
    11.2), well inside the envelope; the model may brake harder than b when it must.
    """

    time_gap_s: float = 1.8
    min_gap_m: float = 4.0
    corridor_half_width_m: float = 1.2
    emergency_ttc_s: float = 1.5  # 0 = no emergency braking
    comfort_accel_mps2: float = 1.5
    comfort_decel_mps2: float = 2.0

    def idm(self, set_speed_mps: float) -> IdmParams:
        return IdmParams(desired_speed_mps=set_speed_mps, time_gap_s=self.time_gap_s,
                         min_gap_m=self.min_gap_m, max_accel_mps2=self.comfort_accel_mps2,
                         comfort_decel_mps2=self.comfort_decel_mps2)


def acc_settings(control: ControlConfig, mode: str) -> AccSettings | None:
    """The ACC a scenario's `[control]` table asks for in estimation `mode`; None when it is off
    or in paper mode (the paper drives at a constant speed: its cases keep it)."""
    if not control.acc or mode == "paper":
        return None
    return AccSettings(control.acc_time_gap_s, control.acc_min_gap_m,
                       control.acc_corridor_half_width_m, control.acc_emergency_ttc_s)


@dataclass(frozen=True)
class Envelope:
    """The accelerations and jerk the ACC may command at one speed."""

    min_accel_mps2: float  # negative: the deepest deceleration
    max_accel_mps2: float
    max_jerk_mps3: float


def envelope(speed_mps: float) -> Envelope:
    """ISO 22179 / ISO 15622 limits at `speed_mps` (see the module's constants)."""
    share = min(max((abs(speed_mps) - V_LOW_MPS) / (V_HIGH_MPS - V_LOW_MPS), 0.0), 1.0)

    def at(pair: tuple[float, float]) -> float:
        return pair[0] + share * (pair[1] - pair[0])

    return Envelope(-at(DECEL_MAX_MPS2), at(ACCEL_MAX_MPS2), at(JERK_MAX_MPS3))


def acc_model_acceleration(p: IdmParams, v: float, gap_m: float = math.inf,
                           lead_speed_mps: float = 0.0) -> float:
    """Kesting et al. (2008)'s ACC model: the IDM, or where the constant-acceleration
    heuristic finds the situation less critical, a blend that follows the CAH:

        a = a_IDM                                               if a_IDM >= a_CAH
        a = (1 - c) a_IDM + c [a_CAH + b tanh((a_IDM - a_CAH) / b)]   otherwise.

    a_CAH is the deceleration that would just match the lead's speed at its present position,
    -(v - v_lead)^2 / (2 s) when closing, 0 otherwise: the CAH with the lead's acceleration
    taken as zero (the radar measures none; the source caps it at the car's own a anyway)."""
    a_idm = idm_acceleration(p, v, gap_m, lead_speed_mps)
    if math.isinf(gap_m) or gap_m <= 0.0:
        return a_idm
    closing = v - lead_speed_mps
    a_cah = -closing * closing / (2.0 * gap_m) if closing > 0.0 else 0.0
    if a_idm >= a_cah:
        return a_idm
    b = p.comfort_decel_mps2
    blended = a_cah + b * math.tanh((a_idm - a_cah) / b)
    return (1.0 - CAH_COOLNESS) * a_idm + CAH_COOLNESS * blended


@dataclass(frozen=True)
class Target:
    """One radar detection as the ACC sees it, on its predicted path."""

    gap_m: float  # the radar's range: the radar sits in the front bumper
    range_rate_mps: float  # + = opening
    speed_mps: float  # its speed along the car's heading (negative: oncoming)
    lateral_m: float  # from the predicted path, + = left

    @property
    def standing(self) -> bool:
        return abs(self.speed_mps) < STATIONARY_MPS

    @property
    def oncoming(self) -> bool:
        return self.speed_mps <= -STATIONARY_MPS

    def ttc_s(self) -> float:
        """Time to collision at the present closing speed; inf when not closing."""
        closing = -self.range_rate_mps
        return self.gap_m / closing if closing > 0.0 else math.inf


def path_curvature_1pm(signals: VehicleSignals) -> float:
    """Curvature of the car's own path now: gyro yaw rate over odometry speed (+ = left)."""
    if not (math.isfinite(signals.yaw_rate_rps) and math.isfinite(signals.speed_mps)):
        return 0.0
    return signals.yaw_rate_rps / max(abs(signals.speed_mps), MIN_PATH_SPEED_MPS)


def path_offset_m(x_m: float, y_m: float, curvature_1pm: float) -> float:
    """Signed distance (+ = left) of the point (x, y) of the vehicle frame from the circular
    arc through the origin along x with `curvature_1pm`."""
    if abs(curvature_1pm) < 1e-6:
        return y_m - 0.5 * curvature_1pm * x_m * x_m
    radius = 1.0 / curvature_1pm  # the centre is at (0, radius)
    return radius - math.copysign(math.hypot(x_m, y_m - radius), radius)


def in_path(reading: RadarReading | None, speed_mps: float, curvature_1pm: float,
            half_width_m: float) -> list[Target]:
    """The detections within `half_width_m` of the arc of `curvature_1pm`, nearest first."""
    if reading is None:
        return []
    out = []
    for d in reading.detections:
        x = reading.mount_x_m + d.range_m * math.cos(d.azimuth_rad)
        y = d.range_m * math.sin(d.azimuth_rad)
        lateral = path_offset_m(x, y, curvature_1pm)
        if abs(lateral) > half_width_m:
            continue
        along = speed_mps + d.range_rate_mps / max(math.cos(d.azimuth_rad), 0.5)
        out.append(Target(d.range_m, d.range_rate_mps, along, lateral))
    return sorted(out, key=lambda t: t.gap_m)


@dataclass(frozen=True)
class AccCommand:
    """One period's decision: the acceleration asked for, whether it is the emergency brake,
    and the target followed (None: a free road)."""

    accel_mps2: float
    emergency: bool
    target: Target | None


class AdaptiveCruise:
    """The ACC for one episode: `__call__(signals)` gives the throttle in [-1, 1] (- = brake),
    `command(signals)` the decision behind it. Keeps state between periods (the path's
    curvature, the target followed, the jerk-limited acceleration, the speed reference);
    `reset` forgets it."""

    def __init__(self, settings: AccSettings, set_speed_mps: float, dt_s: float) -> None:
        if dt_s <= 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        self.settings = settings
        self.set_speed_mps = set_speed_mps
        self.dt_s = dt_s
        self.idm = settings.idm(set_speed_mps)
        self.speed = SpeedController(set_speed_mps, dt_s)
        self.reset()

    def reset(self) -> None:
        self.speed.reset()
        self.speed.target_mps = self.set_speed_mps
        self.accel_mps2 = 0.0
        self.reference_mps: float | None = None
        self.curvature_1pm: float | None = None
        self.target: Target | None = None

    def path(self, signals: VehicleSignals) -> float:
        """The predicted path's curvature: this period's, low-passed (updates the state)."""
        now = path_curvature_1pm(signals)
        if self.curvature_1pm is None:
            self.curvature_1pm = now
        else:
            self.curvature_1pm += (now - self.curvature_1pm) * self.dt_s / (
                PATH_TIME_CONSTANT_S + self.dt_s)
        return self.curvature_1pm

    def select(self, signals: VehicleSignals) -> Target | None:
        """The target to follow: the nearest moving object in the corridor that is not
        oncoming, or last period's target where it now is (within the wider hold band)."""
        half = self.settings.corridor_half_width_m
        for t in in_path(signals.radar, signals.speed_mps, self.path(signals), HOLD_FACTOR * half):
            if t.oncoming:
                continue
            if self._continues(t) or (abs(t.lateral_m) <= half and not t.standing):
                return t
        return None

    def _continues(self, t: Target) -> bool:
        """Whether `t` is where last period's target would be now."""
        last = self.target
        if last is None:
            return False
        expected = last.gap_m + last.range_rate_mps * self.dt_s
        return abs(t.gap_m - expected) <= ASSOCIATION_GATE_M

    def command(self, signals: VehicleSignals) -> AccCommand:
        """This period's acceleration (updates the state)."""
        v = max(signals.speed_mps, 0.0)
        target = self.target = self.select(signals)
        if target is not None and target.ttc_s() < self.settings.emergency_ttc_s:
            self.accel_mps2 = -AEB_DECEL_MPS2
            return AccCommand(self.accel_mps2, True, target)
        if target is None:
            wanted = acc_model_acceleration(self.idm, v)
        else:
            wanted = acc_model_acceleration(self.idm, v, target.gap_m,
                                            max(target.speed_mps, 0.0))
        limits = envelope(v)
        wanted = min(max(wanted, limits.min_accel_mps2), limits.max_accel_mps2)
        step = limits.max_jerk_mps3 * self.dt_s
        held = min(max(self.accel_mps2, limits.min_accel_mps2), limits.max_accel_mps2)
        self.accel_mps2 = held + min(max(wanted - held, -step), step)
        return AccCommand(self.accel_mps2, False, target)

    def __call__(self, signals: VehicleSignals) -> float:
        v = signals.speed_mps
        if not math.isfinite(v):
            return 0.0
        decision = self.command(signals)
        if decision.emergency:
            self.reference_mps = None  # afterwards the reference starts from the speed
            return -1.0
        reference = v if self.reference_mps is None else self.reference_mps
        reference = min(max(reference + decision.accel_mps2 * self.dt_s,
                            v - REFERENCE_LEAD_MPS), v + REFERENCE_LEAD_MPS)
        self.reference_mps = min(max(reference, 0.0), self.set_speed_mps)
        self.speed.target_mps = self.reference_mps
        return self.speed(v)
