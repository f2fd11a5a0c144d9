"""MOBIL (lanekeep/traffic/mobil.py) on cases worked by hand."""

from __future__ import annotations

import pytest

from lanekeep.traffic.mobil import MobilParams, incentive, safety_ok, wants_change

P = MobilParams()  # p = 0.3, Δa_th = 0.1, b_safe = 4


def test_refused_by_safety_however_large_the_gain():
    # own 0 -> 1.0 (+1.0), but the new follower would brake at 5 > b_safe = 4
    args = dict(own_before=0.0, own_after=1.0, new_follower_before=0.0,
                new_follower_after=-5.0, old_follower_before=0.0, old_follower_after=0.0)
    assert not safety_ok(P, -5.0)
    assert safety_ok(P, -4.0)  # exactly b_safe is allowed
    assert not wants_change(P, **args)
    assert not wants_change(MobilParams(politeness=0.0), **args)  # even a selfish driver


def test_refused_by_politeness():
    # own 0.2 -> 0.7 (+0.5); new follower 0 -> -1.5 (safe, but a loss of 1.5); old 0 -> 0
    # p = 0.3: 0.5 + 0.3 (-1.5 + 0) = 0.05 <= 0.1: stays; p = 0: 0.5 > 0.1: changes
    args = (0.2, 0.7, 0.0, -1.5, 0.0, 0.0)
    assert incentive(P, *args) == pytest.approx(0.05, abs=1e-12)
    assert not wants_change(P, *args)
    assert wants_change(MobilParams(politeness=0.0), *args)


def test_accepted():
    # own 0.2 -> 0.8 (+0.6); new follower 0.3 -> 0.1 (-0.2); old follower -0.5 -> 0.3 (+0.8)
    # 0.6 + 0.3 (-0.2 + 0.8) = 0.78 > 0.1
    args = (0.2, 0.8, 0.3, 0.1, -0.5, 0.3)
    assert incentive(P, *args) == pytest.approx(0.78, abs=1e-12)
    assert wants_change(P, *args)
    assert not wants_change(MobilParams(threshold_mps2=0.8), *args)


def test_keep_right_rules():
    # bias 0.3: own 0.5 -> 0.4 (-0.1); new follower 0 -> -1.0; old follower 0 -> 0.2
    # right: -0.1 + 0.3 (0.2) + 0.3 = 0.26 > 0.1 (the new follower's loss is not counted)
    # left:  -0.1 + 0.3 (-1.0) - 0.3 = -0.7
    # symmetric (to_right None): -0.1 + 0.3 (-1.0 + 0.2) = -0.34
    keep_right = MobilParams(keep_right_bias_mps2=0.3)
    args = (0.5, 0.4, 0.0, -1.0, 0.0, 0.2)
    assert incentive(keep_right, *args, to_right=True) == pytest.approx(0.26, abs=1e-12)
    assert incentive(keep_right, *args, to_right=False) == pytest.approx(-0.7, abs=1e-12)
    assert incentive(keep_right, *args) == pytest.approx(-0.34, abs=1e-12)
    assert wants_change(keep_right, *args, to_right=True)
    assert not wants_change(keep_right, *args, to_right=False)
    # without a bias the side does not matter
    assert incentive(P, *args, to_right=True) == incentive(P, *args, to_right=False)


@pytest.mark.parametrize("field", ["politeness", "threshold_mps2", "safe_decel_mps2",
                                   "keep_right_bias_mps2"])
def test_parameters_are_checked(field):
    with pytest.raises(ValueError, match=field):
        MobilParams(**{field: -0.1})
    with pytest.raises(ValueError, match="safe_decel_mps2"):
        MobilParams(safe_decel_mps2=0.0)
