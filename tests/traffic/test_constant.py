"""The constant-speed traffic of before IDM, behind the flow's interface."""

import pytest

from lanekeep.traffic.constant import ConstantFlow
from lanekeep.traffic.state import VehicleSetup


def test_vehicles_drive_at_their_speed_through_everything_and_wrap_on_a_ring():
    flow = ConstantFlow((-1.75, 1.75), 100.0, True, [
        VehicleSetup("a", 0, 90.0, 10.0), VehicleSetup("b", 1, 5.0, 20.0, direction=-1),
        VehicleSetup("c", 0, 95.0, 5.0)])  # c runs into a: nothing stops it
    for _ in range(20):
        flow.step(0.1)
    assert flow.time_s == pytest.approx(2.0)
    a, b, c = flow.states
    assert a.s_m == pytest.approx(10.0) and a.r_m == -1.75  # 90 + 20, wrapped at 100
    assert b.s_m == pytest.approx(65.0) and b.direction == -1  # 5 - 40, wrapped
    assert c.s_m == pytest.approx(5.0)
    flow.reset()
    assert flow.state("a").s_m == 90.0
