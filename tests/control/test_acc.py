"""The adaptive cruise (lanekeep/control/acc.py) on synthetic signals: a free road brings the car
to the set speed; a slower lead close ahead makes it brake; what it commands stays in the ISO
envelope except for the emergency brake; objects off the predicted path, oncoming ones and
standing objects never seen moving are not followed nor braked for; a lead that stops is; the
switch keeps the plain speed PI when off and in paper mode."""

from __future__ import annotations

import dataclasses
import math

import pytest

from lanekeep.control.acc import (
    AEB_DECEL_MPS2,
    AccSettings,
    AdaptiveCruise,
    acc_settings,
    envelope,
    path_offset_m,
)
from lanekeep.control.base import ControlContext
from lanekeep.control.pid import SpeedController
from lanekeep.control.registry import PidController
from lanekeep.control.stanley import StanleyController
from lanekeep.core.signals import RadarDetection, RadarReading, VehicleSignals
from lanekeep.geometry.car import CarGeometry
from lanekeep.scenario.schema import ControlConfig, InvalidValue, load_scenario

DT_S = 0.1
SET_MPS = 15.0
MOUNT_M = 2.4


def _signals(speed_mps: float, *detections: tuple[float, float, float],
             yaw_rate_rps: float = 0.0) -> VehicleSignals:
    """Signals with radar detections given as (range, azimuth, range rate)."""
    reading = RadarReading(tuple(RadarDetection(*d) for d in detections), MOUNT_M)
    return VehicleSignals(speed_mps, yaw_rate_rps, 0.0, 0.0, 0.0, radar=reading)


def _cruise(**settings) -> AdaptiveCruise:
    return AdaptiveCruise(AccSettings(**settings), SET_MPS, DT_S)


def _follow(cruise: AdaptiveCruise, speed_mps: float, gap_m: float, lead_mps,
            seconds: float) -> list[tuple[float, float, float, bool]]:
    """A point-mass car that does what the ACC commands, behind a lead at `lead_mps(t)`
    straight ahead: (speed, gap, command, emergency) per period."""
    out = []
    for k in range(round(seconds / DT_S)):
        lead = lead_mps(k * DT_S)
        command = cruise.command(_signals(speed_mps, (gap_m, 0.0, lead - speed_mps)))
        speed_mps = max(speed_mps + command.accel_mps2 * DT_S, 0.0)
        gap_m += (lead - speed_mps) * DT_S
        out.append((speed_mps, gap_m, command.accel_mps2, command.emergency))
    return out


def _within_envelope(run) -> bool:
    return all(a >= envelope(v).min_accel_mps2 - 1e-9 and a <= envelope(v).max_accel_mps2 + 1e-9
               for v, _, a, emergency in run if not emergency)


def test_the_envelope_is_iso_s_at_both_ends_and_linear_between():
    assert envelope(5.0) == envelope(0.0) == envelope(-3.0)
    low, high, mid = envelope(5.0), envelope(20.0), envelope(12.5)
    assert (low.min_accel_mps2, low.max_accel_mps2, low.max_jerk_mps3) == (-5.0, 4.0, 5.0)
    assert (high.min_accel_mps2, high.max_accel_mps2, high.max_jerk_mps3) == (-3.5, 2.0, 2.5)
    assert envelope(30.0) == high
    assert mid.min_accel_mps2 == pytest.approx(-4.25) and mid.max_accel_mps2 == pytest.approx(3.0)


def test_the_path_offset_is_zero_on_the_arc_and_signed_left():
    for curvature in (0.0, 1e-3, -1e-2, 0.05):
        for s in (5.0, 30.0, 60.0):
            if curvature:
                x = math.sin(s * curvature) / curvature
                y = (1 - math.cos(s * curvature)) / curvature
            else:
                x, y = s, 0.0
            assert path_offset_m(x, y, curvature) == pytest.approx(0.0, abs=1e-9)
            heading = s * curvature  # 0.5 m along the arc's left normal there
            left = (x - 0.5 * math.sin(heading), y + 0.5 * math.cos(heading))
            assert path_offset_m(*left, curvature) == pytest.approx(0.5, abs=1e-6)


def test_a_free_road_brings_the_car_to_the_set_speed_and_not_beyond():
    cruise, speed = _cruise(), 8.0
    speeds = []
    for _ in range(300):
        command = cruise.command(_signals(speed))
        assert command.target is None and not command.emergency
        speed += command.accel_mps2 * DT_S
        speeds.append(speed)
    assert max(speeds) <= SET_MPS + 1e-6
    assert speeds[-1] == pytest.approx(SET_MPS, abs=0.15)
    assert _cruise()(_signals(8.0)) > 0.0  # throttle, not brake


def test_no_radar_reading_is_a_free_road():
    cruise = _cruise()
    command = cruise.command(VehicleSignals(SET_MPS, 0.0, 0.0, 0.0, 0.0))
    assert command.target is None and command.accel_mps2 == pytest.approx(0.0, abs=1e-6)


def test_a_slower_lead_close_ahead_brakes_the_car():
    cruise = _cruise()
    throttles = [cruise(_signals(SET_MPS, (15.0, 0.0, -5.0))) for _ in range(5)]
    assert cruise.target is not None and cruise.target.speed_mps == pytest.approx(10.0)
    assert cruise.accel_mps2 < -1.0 and throttles[-1] < 0.0


def test_the_car_settles_behind_a_slower_lead_at_its_time_gap():
    run = _follow(_cruise(), SET_MPS, 80.0, lambda t: 10.0, 80.0)
    speed, gap, _, _ = run[-1]
    assert speed == pytest.approx(10.0, abs=0.1)
    # the IDM's equilibrium gap: (s0 + v T) / sqrt(1 - (v / v0)^4)
    assert gap == pytest.approx((4.0 + 10.0 * 1.8) / math.sqrt(1 - (10.0 / SET_MPS) ** 4), abs=1.0)
    assert min(g for _, g, _, _ in run) > 4.0
    assert not any(e for *_, e in run) and _within_envelope(run)


def test_a_cut_in_brakes_at_the_envelope_s_limit_after_the_jerk_ramp_never_beyond():
    cruise = _cruise()
    commands = [cruise.command(_signals(SET_MPS, (16.0, 0.0, -8.0))) for _ in range(20)]
    limits = envelope(SET_MPS)
    assert not any(c.emergency for c in commands)  # TTC = 2 s
    accels = [c.accel_mps2 for c in commands]
    assert min(accels) == pytest.approx(limits.min_accel_mps2)
    assert all(a >= limits.min_accel_mps2 - 1e-12 for a in accels)
    steps = [b - a for a, b in zip([0.0, *accels], accels, strict=False)]
    assert all(abs(s) <= limits.max_jerk_mps3 * DT_S + 1e-12 for s in steps)
    assert accels.index(min(accels)) <= round(1.5 / DT_S)  # there within ~a second


def test_a_lead_that_brakes_hard_is_followed_within_the_envelope_until_the_emergency_brake():
    def lead(t):  # 12 m ahead at 15 m/s, brakes at once at 9 m/s^2, beyond the ACC's 4
        return max(SET_MPS - 9.0 * t, 0.0)

    run = _follow(_cruise(), SET_MPS, 12.0, lead, 12.0)
    assert _within_envelope(run)
    emergency = [a for *_, a, e in run if e]
    assert emergency and all(a == -AEB_DECEL_MPS2 for a in emergency)
    assert min(g for _, g, _, _ in run) > 0.0 and run[-1][0] == 0.0


def test_the_emergency_brake_is_full_braking():
    cruise = _cruise()
    assert cruise(_signals(SET_MPS, (10.0, 0.0, -10.0))) == -1.0  # TTC 1 s
    command = cruise.command(_signals(SET_MPS, (10.0, 0.0, -10.0)))
    assert command.emergency and command.accel_mps2 == -AEB_DECEL_MPS2
    assert not _cruise(emergency_ttc_s=0.0).command(_signals(SET_MPS, (10.0, 0.0, -10.0))).emergency


def test_a_detection_in_the_next_lane_is_ignored():
    azimuth = math.atan2(3.5, 30.0)  # 3.5 m left of a straight path, 30 m ahead
    command = _cruise().command(_signals(SET_MPS, (30.0, azimuth, -5.0)))
    assert command.target is None and command.accel_mps2 >= 0.0


def test_in_a_bend_the_path_not_the_heading_decides():
    curvature = 1.0 / 100.0  # a left bend the car is turning through
    yaw = curvature * SET_MPS
    # On the arc 40 m on: a lead there is followed; a tree straight ahead is not.
    s = 40.0
    x, y = math.sin(s * curvature) / curvature - MOUNT_M, (1 - math.cos(s * curvature)) / curvature
    on_arc = (math.hypot(x, y), math.atan2(y, x), -4.0)
    ahead = (38.0, 0.0, -4.0)
    command = _cruise().command(_signals(SET_MPS, on_arc, ahead, yaw_rate_rps=yaw))
    assert command.target is not None and command.target.gap_m == pytest.approx(on_arc[0])
    command = _cruise().command(_signals(SET_MPS, ahead, yaw_rate_rps=yaw))
    assert command.target is None


def test_oncoming_and_unseen_standing_objects_are_neither_followed_nor_braked_for():
    oncoming = (15.0, 0.0, -SET_MPS - 12.0)  # TTC 0.6 s
    standing = (15.0, 0.0, -SET_MPS)  # TTC 1 s: a guard rail where a bend begins, or a car
    for detection in (oncoming, standing):
        command = _cruise().command(_signals(SET_MPS, detection))
        assert command.target is None and not command.emergency and command.accel_mps2 >= 0.0


def test_a_followed_lead_that_stops_short_is_an_emergency():
    cruise = _cruise()
    assert not cruise.command(_signals(SET_MPS, (15.1, 0.0, -1.0))).emergency
    command = cruise.command(_signals(SET_MPS, (15.0, 0.0, -SET_MPS)))  # stopped dead
    assert command.emergency and command.target is not None and command.target.standing


def test_a_lead_that_stops_stays_the_target_and_the_car_stops_behind_it():
    def lead(t):
        return 10.0 if t < 3.0 else max(10.0 - 2.0 * (t - 3.0), 0.0)

    cruise = _cruise()
    run = _follow(cruise, 10.0, 25.0, lead, 40.0)
    speed, gap, _, _ = run[-1]
    assert cruise.target is not None and cruise.target.standing
    assert speed == pytest.approx(0.0, abs=0.05)
    assert 3.0 < gap < 8.0 and min(g for _, g, _, _ in run) > 3.0
    assert _within_envelope(run)


def test_the_throttle_holds_the_speed_when_following_at_equilibrium():
    cruise = _cruise()
    throttles = [cruise(_signals(10.0, (24.6, 0.0, 0.0))) for _ in range(50)]
    # the speed PI's own feed-forward and integrator at a steady 10 m/s reference
    assert abs(throttles[-1]) < 0.2 and cruise.reference_mps == pytest.approx(10.0, abs=0.3)


def _context(**control) -> ControlContext:
    scenario = load_scenario("clear_straight")
    scenario = dataclasses.replace(scenario,
                                   control=dataclasses.replace(scenario.control, **control))
    return ControlContext.of(scenario, CarGeometry())


def test_acc_is_off_by_default_and_in_paper_mode():
    assert ControlConfig().acc is False and _context().acc is None
    assert _context().adaptive_cruise() is None
    on = _context(acc=True, acc_time_gap_s=2.0)
    assert on.acc == AccSettings(time_gap_s=2.0)
    paper = dataclasses.replace(ControlConfig(acc=True))
    assert acc_settings(paper, "paper") is None and acc_settings(paper, "default") is not None


@pytest.mark.parametrize("controller", [PidController, StanleyController])
def test_with_acc_off_the_throttle_is_the_speed_pi_s_to_the_bit(controller):
    plain = controller(_context())
    reference = SpeedController(SET_MPS, DT_S)
    estimate = type("Estimate", (), {"centre": None, "offset_m": None, "offset_x_m": 8.0})()
    for speed in (12.0, 13.7, 15.2, 14.9):
        signals = _signals(speed, (10.0, 0.0, -5.0))
        assert plain.control(estimate, signals)[1] == reference(speed)


@pytest.mark.parametrize("controller", [PidController, StanleyController])
def test_with_acc_on_the_controllers_brake_for_a_slower_lead(controller):
    ctl = controller(_context(acc=True))
    estimate = type("Estimate", (), {"centre": None, "offset_m": None, "offset_x_m": 8.0})()
    throttles = [ctl.control(estimate, _signals(SET_MPS, (12.0, 0.0, -4.0)))[1]
                 for _ in range(5)]
    assert throttles[-1] < 0.0
    ctl.reset()
    assert ctl.acc.target is None and ctl.acc.accel_mps2 == 0.0


def test_an_acc_setting_out_of_range_is_refused_naming_the_key():
    with pytest.raises(InvalidValue, match="acc_time_gap_s"):
        ControlConfig(acc_time_gap_s=0.5)
    with pytest.raises(InvalidValue, match="acc_emergency_ttc_s"):
        ControlConfig(acc_emergency_ttc_s=math.nan)
