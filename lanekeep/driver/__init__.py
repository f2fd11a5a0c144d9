"""What the car runs: detectors, roll and odometry filters, the lane estimator and the
controller, built from one `DriverConfig`, stepped as `Driver.step(Observation) -> (Command,
Belief)`. It sees camera frames and the car's sensor signals only: this package never imports
the world, sensing, scoring, the loop, MuJoCo or dm_control (tests/project/test_layers.py)."""
