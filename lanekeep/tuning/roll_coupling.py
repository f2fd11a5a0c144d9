"""The body roll compensation's constants (estimators/roll.py), fitted on the tuning curves.

With the compensation off, by least squares: the roll gradient (the body's true roll against
the lateral accelerometer's signal, low-passed and clipped as the loop does, `RollFilter`) and,
per detector, its lever (the offset error, detection minus the true offset at its look-ahead,
against the true roll, in metres of offset per radian). The truth (roll, offsets) is read here
only, to calibrate; the loop then uses the accelerometer alone.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

CURVES = ("tune_right_curve_r100", "tune_left_curve_r200_rain", "tune_gentle_s_curve_r700_r500",
          "tune_sharp_right_r45")
CORE_M = 0.5  # an offset error this large is a wild fit, not roll


def default_scenarios(tuning_dir: Path) -> list[str]:
    """The tuning scenarios with curves enough to roll the body: the files of CURVES."""
    return [str(Path(tuning_dir) / f"{name}.toml") for name in CURVES]


def samples(path: str) -> dict[str, list[tuple[float, float, float]]]:
    """Per source: (offset error m, filtered lateral acceleration m/s^2, true roll rad) per
    step."""
    from lanekeep.estimators.roll import RollCompensation, RollFilter
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_offsets

    scenario = load_scenario(path)
    est = dataclasses.replace(scenario.estimation, roll_gradient_deg_per_mps2=0.0)
    scenario = dataclasses.replace(scenario, estimation=est)
    out: dict[str, list[tuple[float, float, float]]] = {}
    accel = RollFilter(RollCompensation(), scenario.control_period_s)
    with Episode(scenario) as episode:
        road, lane = episode.world.road, scenario.road.ego_lane
        for _ in range(episode.total_steps):
            step = episode.step()
            rot = episode.world.car.rotation()
            roll = float(np.arctan2(rot[2, 1], rot[2, 2]))
            accel.update(step.signals.accel_lat_mps2)
            for name, e in step.estimates.items():
                if e.valid:
                    truth = float(lane_offsets(road, *step.sensed_pose, lane, [e.x_m])[0])
                    out.setdefault(name, []).append(
                        (e.offset_m - truth, accel.accel_lat_mps2, roll))
    return out


def slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y on x, with an intercept."""
    return float(np.linalg.lstsq(np.c_[x, np.ones_like(x)], y, rcond=None)[0][0])


@dataclass(frozen=True)
class Lever:
    """One source's lever and what roll explains of its offset error."""

    lever_m_per_rad: float
    rms_m: float  # the offset error's RMS over the core steps
    rest_rms_m: float  # the same less the lever times the roll
    steps: int  # core steps (error under CORE_M)


def lever(rows: list[tuple[float, float, float]]) -> Lever:
    """A source's lever from its `samples` rows."""
    err, _accel, roll = np.array(rows).T
    core = np.abs(err) < CORE_M
    value = slope(roll[core], err[core])
    rest = err[core] - value * roll[core]
    return Lever(value, float(np.sqrt(np.mean(err[core] ** 2))),
                 float(np.sqrt(np.mean(rest ** 2))), int(core.sum()))


def roll_gradient_deg(reference_rows: list[tuple[float, float, float]]) -> float:
    """Degrees of roll per m/s^2 of filtered lateral acceleration, over the reference's rows
    (one a step the reference was valid)."""
    _err, accel, roll = np.array(reference_rows).T
    return float(np.degrees(slope(accel, roll)))


def front_lever(levers: dict[str, Lever]) -> float:
    """The front models' lever: the median of theirs (every source but the reference)."""
    return float(np.median([v.lever_m_per_rad for k, v in levers.items() if k != "reference"]))
