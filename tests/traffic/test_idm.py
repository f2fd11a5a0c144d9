"""The IDM (lanekeep/traffic/idm.py) against values worked by hand from the formula."""

from __future__ import annotations

import math

import pytest

from lanekeep.traffic.idm import MAX_DECEL_MPS2, IdmParams, desired_gap, idm_acceleration

P = IdmParams()  # v0 = 30 m/s, T = 1.5 s, s0 = 2 m, a = 1.0, b = 1.5, delta = 4


def test_free_road_from_standstill_is_the_maximum_acceleration():
    # a [1 - (0 / 30)^4] = a = 1.0
    assert idm_acceleration(P, 0.0) == pytest.approx(1.0, abs=1e-12)


def test_free_road_at_the_desired_speed_is_zero():
    # a [1 - (30 / 30)^4] = 0
    assert idm_acceleration(P, 30.0) == pytest.approx(0.0, abs=1e-12)


def test_free_road_halfway():
    # 1.0 [1 - (15 / 30)^4] = 1 - 1/16 = 0.9375
    assert idm_acceleration(P, 15.0) == pytest.approx(0.9375, abs=1e-12)


def test_desired_gap():
    # s* = 2 + 20 * 1.5 + 20 * 5 / (2 sqrt(1.0 * 1.5)) = 2 + 30 + 100 / 2.449490 = 72.824829
    assert desired_gap(P, 20.0, 5.0) == pytest.approx(72.824829, abs=1e-6)
    # a leader pulling away fast: v T + v dv / (2 sqrt(ab)) = 30 - 20 * 20 / 2.449 < 0 -> s0
    assert desired_gap(P, 20.0, -20.0) == pytest.approx(2.0, abs=1e-12)


def test_a_leader_at_the_equilibrium_gap_gives_no_acceleration():
    # v = 20, v_lead = 20: s*(20, 0) = 2 + 20 * 1.5 = 32 m; 1 - (20/30)^4 = 65/81;
    # s_e = 32 / 0.895806 = 35.72200 m, where a [1 - 16/81 - (32 / s_e)^2] = 0
    s_e = 32.0 / math.sqrt(65.0 / 81.0)
    assert s_e == pytest.approx(35.72200, abs=1e-5)
    assert idm_acceleration(P, 20.0, s_e, 20.0) == pytest.approx(0.0, abs=1e-12)
    assert idm_acceleration(P, 20.0, s_e + 1.0, 20.0) > 0.0 > idm_acceleration(P, 20.0, s_e - 1.0,
                                                                                20.0)


def test_closing_on_a_slower_leader():
    # v = 20, v_lead = 15 (dv = 5), gap 30 m: s* = 72.824829 (above);
    # (s* / s)^2 = (72.824829 / 30)^2 = 2.4274943^2 = 5.8927286; (v / v0)^4 = 16/81 = 0.1975309
    # a = 1.0 (1 - 0.1975309 - 5.8927286) = -5.0902595
    assert idm_acceleration(P, 20.0, 30.0, 15.0) == pytest.approx(-5.0902595, abs=1e-6)


def test_no_lead_speed_is_a_standing_obstacle():
    assert idm_acceleration(P, 10.0, 50.0) == idm_acceleration(P, 10.0, 50.0, 0.0)


def test_overlap_and_hopeless_gaps_give_the_floor_never_nan():
    for gap in (0.0, -3.0, 1e-9):
        acc = idm_acceleration(P, 30.0, gap, 0.0)
        assert acc == -MAX_DECEL_MPS2
    # far above v0: (90 / 30)^4 = 81 -> -80, clamped
    assert idm_acceleration(P, 90.0) == -MAX_DECEL_MPS2


def test_a_driver_who_wants_to_stand():
    stand = IdmParams(desired_speed_mps=0.0)
    assert idm_acceleration(stand, 5.0) == -1.5  # brakes at b
    assert idm_acceleration(stand, 0.0) == 0.0  # and holds
    assert idm_acceleration(stand, 0.0, 100.0, 10.0) == 0.0  # a leader pulling away: stays
    # closing fast: the interaction brakes harder than b. s* = 2 + 15 + 10 * 10 / 2.449490
    # = 57.824829; 1.0 [1 - (57.824829 / 20)^2] = 1 - 2.8912415^2 = 1 - 8.3592771
    assert idm_acceleration(stand, 10.0, 20.0, 0.0) == pytest.approx(-7.3592771, abs=1e-6)


@pytest.mark.parametrize("field", ["time_gap_s", "min_gap_m", "max_accel_mps2",
                                   "comfort_decel_mps2", "delta"])
def test_parameters_must_be_positive(field):
    with pytest.raises(ValueError, match=field):
        IdmParams(**{field: 0.0})
    with pytest.raises(ValueError, match="desired_speed_mps"):
        IdmParams(desired_speed_mps=-1.0)
    with pytest.raises(ValueError, match="time_gap_s"):
        IdmParams(time_gap_s=math.nan)
