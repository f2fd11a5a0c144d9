"""The tuning scenarios: the TOML files beside this file, package data found with
importlib.resources (`lanekeep.tuning.scenarios.tuning_dir`). `lanekeep bench` scores none of
them, so the tuning tools measure and choose here, never on lanekeep/scenario/shipped/."""
