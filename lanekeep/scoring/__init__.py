"""The truth of the lane (from the road geometry), per-step metrics, safety among other vehicles
(gap, time to collision, contact, hard braking) and pass/fail criteria: with report, the only
readers of the simulator's state."""
