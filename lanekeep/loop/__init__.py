"""The closed loop: Episode (sense, detect, estimate, control, actuate, score, record), paper mode,
the runner (episodes in worker processes) and the perf benchmark."""
