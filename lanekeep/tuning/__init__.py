"""Measurement and tuning, run on the tuning scenarios (lanekeep/tuning/scenario_files/*.toml,
package data), never on the seeds `lanekeep bench` scores (tuning on the bench's scenarios would
tune on its test set).

One concept a module, each with its command line: `python -m lanekeep.tuning.<module> --help`
(tools/ keeps a short script per command for a clone's older instructions). `scenarios` (which
scenarios a tool may measure on), `detector_noise` (the tracker's measurement covariances),
`estimation` (an `[estimation]` key compared in the closed loop), `replay` (the estimator's
inputs recorded once, replayed open loop), `trace` (why the output beats or loses to a model),
`roll_coupling` (body roll compensation's constants), `criteria_calibration` (the shipped
scenarios' pass/fail limits on tuning seeds), `detector_replay` (recorded frames through the
classical detectors), `decode_priors` (LaneNet's decoding priors on the validation split),
`real_accuracy` (the detectors on labelled real frames), `realism` and `realism_report`
(renders beside real photos, by the same image statistics), `shade_ratio` (the shade/sun luma
of the shadow scenarios), `antialiasing` (what anti-aliasing does to the detectors),
`contact_sheet` (every scenario's cameras at two poses on one image).
"""
