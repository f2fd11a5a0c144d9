"""The estimator's string choices, in one place: the scenario format validates a file's
`[estimation]` against them and `EstimatorSettings` refuses anything else (a misspelt choice
would otherwise fall through to another branch). No imports, so loading a scenario does not
load the estimators."""

RESIDUAL_MODES = ("distance_aligned", "one_step_delay")
OUTPUT_MODES = ("select", "fused", "precision")
MODEL_LANES = ("track", "detection")
MMAE_PRIORS = ("uniform", "precision")
OUTPUT_AT = ("lookahead", "nearest_row")  # the estimator's own; paper mode sets nearest_row
MMAE_INPUTS = ("track", "detection")  # the estimator's own; paper mode sets detection
