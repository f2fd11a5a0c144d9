"""The one-step carry of a lane by the car's own motion (lanekeep/tuning/ego_carry.py)."""

import math

import numpy as np

from lanekeep.tuning.ego_carry import CarryStep, carry_errors, main


def _swinging_car(seconds: float = 6.0, dt: float = 0.1, substeps: int = 200) -> list[CarryStep]:
    """A car at 15 m/s on a straight road, its heading swinging +-0.07 rad with a period of
    2.4 s (a car weaving across its lane, as the two-model loop does beside a truck): per
    frame, the road's centre line in the car's frame and the exact speed and yaw rate."""
    v, amplitude, omega = 15.0, 0.07, 2.0 * math.pi / 2.4
    y, t, steps = 0.3, 0.0, []
    h = dt / substeps
    for _ in range(int(round(seconds / dt)) + 1):
        heading = amplitude * math.sin(omega * t)
        steps.append(CarryStep((-y / math.cos(heading), -math.tan(heading), 0.0), v,
                               amplitude * omega * math.cos(omega * t)))
        for _ in range(substeps):  # the motion over the period, finely integrated
            y += v * math.sin(amplitude * math.sin(omega * (t + 0.5 * h))) * h
            t += h
    return steps


def test_the_motion_handed_on_carries_a_lane_closer_than_the_end_sample():
    """The period's mean (what DeadReckoning hands on) carries the weaving car's lane to the
    next frame within a fraction of what the sample at the period's end does; without the yaw
    the carry is worse still."""
    errors = carry_errors(_swinging_car(), dt_s=0.1, at_m=4.0, lever_m=0.0)
    rms = {name: float(np.sqrt(np.mean(np.square(e)))) for name, e in errors.items()}
    assert rms["handed_on"] < 0.3 * rms["end_sample"]
    assert rms["end_sample"] < rms["no_yaw"]
    assert rms["handed_on"] < 0.005  # m, per step, at 4 m


def test_a_bad_seed_count_is_one_error_line(capsys):
    try:
        main(["--seeds", "0"])
    except SystemExit as stop:
        assert stop.code == 2
    assert "--seeds must be >= 1" in capsys.readouterr().err


def test_a_missing_scenario_is_one_error_line(capsys, tmp_path):
    assert main([str(tmp_path / "nowhere.toml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego_carry: error:") and err.count("\n") == 1
