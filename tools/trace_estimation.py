"""Why the fused output beats or loses to a model: per-model bias, spread, MMAE weight, and
what the reference can see of them.

    MUJOCO_GL=egl .venv/bin/python tools/trace_estimation.py night [--output fused]

Runs one episode (a shipped scenario's name or a scenario file) and prints, per front model,
its own track's offset error at the output's look-ahead (RMSE, mean = bias, standard
deviation), its curvature error, and its mean MMAE probability; then the same errors of the
output and of the rear reference.

Then what the MMAE was given to tell the models apart: per model, the mean and RMS of its
residual (eq. 2: the reference minus the model's offset carried to where the reference looked),
and the correlation between the reference's error and the carried offset's error. The residual
is scored step by step, so a model whose errors rise and fall with the reference's (a positive
correlation: the same network reading the same stretch of road from the other camera) keeps a
small residual whatever its bias, and one whose errors run against the reference's pays for
both. Then each detection's left and right boundary error at the look-ahead: a bias on one
side only is the detector's (a marking lit on one side), not the lane's. Last, when the output
accrues its squared error beyond the best own track's, window by window (`--window`, s), with
the models' mean probabilities there: a loss made in the first second, before the reference
can see road the front models saw, is the prior's; one spread over the episode is the MMAE's.

Truth is read here for scoring only, as in `lanekeep run`. The code is lanekeep/tuning/trace.py.
"""

from __future__ import annotations

import argparse

import numpy as np

from lanekeep.tuning.trace import report, trace


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", help="a shipped scenario's name or a scenario file")
    parser.add_argument("--output", choices=("select", "fused", "precision"),
                        help="[estimation] output instead of the scenario's")
    parser.add_argument("--window", type=float, default=2.0,
                        help="seconds per row of the output's excess over the best track")
    args = parser.parse_args(argv)
    if not (np.isfinite(args.window) and args.window > 0):
        parser.error(f"--window must be a positive number of seconds, got {args.window}")
    names, columns = trace(args.scenario, args.output)
    print("\n".join(report(names, columns, args.window)))


if __name__ == "__main__":
    main()
