"""Run one closed-loop episode of a shipped scenario and print its report.

    python examples/run_episode.py clear_curve
    python examples/run_episode.py clear_straight --seconds 3 --size 320x180   # quick
"""

import argparse
import dataclasses

from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="clear_straight",
                        help="a shipped scenario's name or a .toml file")
    parser.add_argument("--seconds", type=float, help="shorter than the scenario's duration")
    parser.add_argument("--size", default=None, help="camera size WxH (default: the scenario's)")
    args = parser.parse_args()

    scenario = load_scenario(args.scenario)
    if args.seconds is not None:
        scenario = dataclasses.replace(scenario, duration_s=args.seconds)
    size = tuple(int(v) for v in args.size.split("x")) if args.size else None

    # An Episode owns MuJoCo renderers: close it (a `with` block does) when done.
    with Episode(scenario, render_size=size) as episode:
        report = episode.run()

    print(report.table())  # the same table `lanekeep run` prints
    fused = report.sources["fused"]
    print(f"\n{report.scenario}: {report.steps} steps, {report.lane_departures} lane departures,"
          f" car RMS {report.car_rms_cm:.1f} cm, MMAE output RMSE {fused.rmse_cm:.1f} cm")


if __name__ == "__main__":
    main()
