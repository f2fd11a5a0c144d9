"""Measurement and tuning: the code behind tools/, run on the tuning scenarios in tools/tuning/,
never on the seeds `lanekeep bench` scores (tuning on the bench's scenarios would tune on its
test set).

One concept a module: `scenarios` (which scenarios a tool may measure on), `detector_noise`
(the tracker's measurement covariances), `estimation` (an `[estimation]` key compared in the
closed loop), `replay` (the estimator's inputs recorded once, replayed open loop), `trace` (why
the output beats or loses to a model), `roll_coupling` (body roll compensation's constants),
`detector_replay` (recorded frames through the classical detectors), `realism` and
`realism_report` (renders beside real photos, by the same image statistics), `contact_sheet`
(every scenario's cameras at two poses on one image). The scripts in
tools/ are their command lines: argparse, a call here, print.
"""
