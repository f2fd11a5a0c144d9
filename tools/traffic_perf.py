"""What one step of the traffic flow (lanekeep/traffic/flow.py) costs, in milliseconds.

    .venv/bin/python tools/traffic_perf.py
    .venv/bin/python tools/traffic_perf.py --counts 30 100 300 --steps 2000

A ring of four same-direction lanes with MOBIL drivers of varied desired speeds and an ego car
driving lane 0 at 25 m/s, stepped at 0.05 s: the median and the 95th percentile of the wall
time of single steps after a warm-up. The flow runs once an episode step beside MuJoCo, so a
step for 30 vehicles should stay well under 1 ms. Wall times depend on the machine and its
load; this prints them and asserts nothing (a unit test never times anything).
"""

from __future__ import annotations

import argparse
import time

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.traffic.flow import TrafficFlow
from lanekeep.traffic.idm import IdmParams
from lanekeep.traffic.mobil import MobilParams
from lanekeep.traffic.state import EgoState, VehicleSetup

LANES = 4
LANE_WIDTH_M = 3.5
DT_S = 0.05
EGO_SPEED_MPS = 25.0


def build(n_vehicles: int, seed: int = 0) -> TrafficFlow:
    """n vehicles spread evenly over the lanes of a ring sized for ~40 m a vehicle a lane."""
    rng = np.random.default_rng(seed)
    per_lane = -(-n_vehicles // LANES)
    length_m = max(1000.0, 40.0 * per_lane)
    centres = [(k - (LANES - 1) / 2) * LANE_WIDTH_M for k in range(LANES)]
    vehicles = [
        VehicleSetup(name=f"v{i}", lane=i % LANES,
                     s_m=(i // LANES) * length_m / per_lane + 10.0 * (i % LANES) + 20.0,
                     speed_mps=float(rng.uniform(15.0, 25.0)),
                     idm=IdmParams(desired_speed_mps=float(rng.uniform(25.0, 35.0))),
                     mobil=MobilParams(politeness=float(rng.uniform(0.0, 0.5))))
        for i in range(n_vehicles)]
    return TrafficFlow(centres, [1] * LANES, length_m, True, vehicles,
                       lane_width_m=LANE_WIDTH_M)


def time_steps(flow: TrafficFlow, steps: int, warmup: int = 200) -> np.ndarray:
    """Wall time (ms) of each of `steps` single steps, after `warmup` untimed ones."""
    centre = -(LANES - 1) / 2 * LANE_WIDTH_M
    times = np.empty(steps)
    for i in range(warmup + steps):
        ego = EgoState(s_m=EGO_SPEED_MPS * DT_S * i, r_m=centre, speed_mps=EGO_SPEED_MPS,
                       length_m=4.6, width_m=1.85)
        start = time.perf_counter()
        flow.step(DT_S, ego)
        if i >= warmup:
            times[i - warmup] = (time.perf_counter() - start) * 1e3
    return times


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[30, 100],
                        help="vehicle counts to time (default: 30 100)")
    parser.add_argument("--steps", type=int, default=2000, help="timed steps per count")
    args = parser.parse_args(argv)
    print(f"{'vehicles':>8}  {'median ms':>9}  {'p95 ms':>7}  off their starting lane")
    for n in args.counts:
        flow = build(n)
        times = time_steps(flow, args.steps)
        lanes = sum(st.lane != i % LANES for i, st in enumerate(flow.states))
        print(f"{n:>8}  {np.median(times):>9.3f}  {np.percentile(times, 95):>7.3f}  "
              f"{lanes}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
