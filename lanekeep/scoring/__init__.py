"""The truth of the lane (from the road geometry), per-step metrics and pass/fail criteria: with
report, the only readers of the simulator's state."""
