"""Vehicle sensors: determinism, noise statistics against the configured magnitudes, the
perfect switch, the [sensors] scenario table, and a real car's accelerations."""

import math

import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.signals import VehicleSignals
from lanekeep.scenario.schema import ScenarioError, parse_scenario
from lanekeep.scenario.sensors import SensorsConfig
from lanekeep.sensing.vehicle_sensors import VehicleSensors

MINIMAL = """
name = "tiny"
description = "a test"
[road]
[[road.segments]]
kind = "straight"
length_m = 100
"""

N_SAMPLES = 20_000  # sample std within ~0.5 % (1-sigma) of the true one
STD_RTOL = 0.03  # 6 standard errors


class FakeCar:
    """Fixed true values with the methods the sensors read; no MuJoCo needed."""

    def __init__(self, speed=15.0, yaw_rate=0.2, accel=(0.5, 3.0, 0.1), steer=0.05):
        self.speed, self.yaw_rate, self.steer = speed, yaw_rate, steer
        self.accel = np.array(accel)

    def speed_mps(self):
        return self.speed

    def yaw_rate_rps(self):
        return self.yaw_rate

    def acceleration_body(self):
        return self.accel.copy()

    def steer_angle_rad(self):
        return self.steer


def _run(config, dt_s=0.1, seed=0, n=5, car=None):
    sensors = VehicleSensors(config, dt_s, np.random.default_rng(seed))
    car = car or FakeCar()
    return [sensors.sample(car) for _ in range(n)]


def _columns(signals):
    """(n, 5) array: speed, yaw rate, accel long, accel lat, steer."""
    return np.array([
        (s.speed_mps, s.yaw_rate_rps, s.accel_long_mps2, s.accel_lat_mps2, s.steer_angle_rad)
        for s in signals
    ])


def test_same_seed_same_signals_different_seed_different():
    config = SensorsConfig()
    first, again = _run(config, seed=7, n=50), _run(config, seed=7, n=50)
    assert first == again
    other = _run(config, seed=8, n=50)
    differs = np.abs(_columns(first) - _columns(other)) > 0
    assert differs[:, 1:4].all()  # gyro and accelerometers differ on every sample


def test_draws_do_not_depend_on_magnitudes():
    """A zero magnitude still consumes its draw, so the stream stays aligned across configs."""
    quiet = SensorsConfig(**{k: 0.0 for k in (
        "speed_scale_sigma", "speed_noise_mps", "speed_resolution_mps",
        "gyro_noise_density_dps_rthz", "gyro_bias_sigma_dps", "gyro_bias_walk_dps_rts",
        "accel_noise_density_mps2_rthz", "steer_noise_deg", "steer_resolution_deg")})
    states = []
    for config in (SensorsConfig(), quiet):
        rng = np.random.default_rng(3)
        sensors = VehicleSensors(config, 0.1, rng)
        for _ in range(10):
            sensors.sample(FakeCar())
        states.append(rng.bit_generator.state)
    assert states[0] == states[1]
    assert _columns(_run(quiet, n=3)) == pytest.approx(np.array([[15.0, 0.2, 0.5, 3.0, 0.05]] * 3))


@pytest.mark.parametrize("dt_s", [0.1, 0.02])
def test_white_noise_std_matches_the_per_sample_sigma(dt_s):
    config = SensorsConfig(speed_resolution_mps=0.0, steer_resolution_deg=0.0,
                           gyro_bias_walk_dps_rts=0.0, steer_noise_deg=0.5)
    car = FakeCar()
    data = _columns(_run(config, dt_s=dt_s, seed=1, n=N_SAMPLES, car=car))
    expected = np.array([
        config.speed_noise_mps,
        math.radians(config.gyro_noise_density_dps_rthz) * math.sqrt(1.0 / dt_s),
        config.accel_noise_density_mps2_rthz * math.sqrt(1.0 / dt_s),
        config.accel_noise_density_mps2_rthz * math.sqrt(1.0 / dt_s),
        math.radians(config.steer_noise_deg) / config.steering_ratio,
    ])
    assert data.std(axis=0, ddof=1) == pytest.approx(expected, rel=STD_RTOL)
    # White noise has no mean: the accelerometers and the steering angle are unbiased.
    standard_error = expected / math.sqrt(N_SAMPLES)
    truth = np.array([car.accel[0], car.accel[1], car.steer])
    assert np.all(np.abs(data[:, [2, 3, 4]].mean(axis=0) - truth) < 5 * standard_error[[2, 3, 4]])


def test_gyro_bias_random_walk_increment_std():
    dt_s, walk = 0.05, 0.02  # deg/s/sqrt(s), far above the default to dominate the readings
    config = SensorsConfig(gyro_noise_density_dps_rthz=0.0, gyro_bias_walk_dps_rts=walk)
    car = FakeCar()
    sensors = VehicleSensors(config, dt_s, np.random.default_rng(2))
    yaw = np.array([sensors.sample(car).yaw_rate_rps for _ in range(N_SAMPLES)])
    assert yaw[0] == pytest.approx(car.yaw_rate + sensors.initial_gyro_bias_rps, abs=1e-15)
    steps = np.diff(yaw)
    assert steps.std(ddof=1) == pytest.approx(math.radians(walk) * math.sqrt(dt_s), rel=STD_RTOL)
    assert abs(steps.mean()) < 5 * math.radians(walk) * math.sqrt(dt_s / N_SAMPLES)
    # reset puts the bias back to its initial offset, not to zero and not re-drawn.
    sensors.reset()
    first_after_reset = sensors.sample(car).yaw_rate_rps
    assert first_after_reset == pytest.approx(yaw[0], abs=1e-15)


def test_per_episode_draws_have_the_configured_spread():
    config = SensorsConfig(speed_noise_mps=0.0, speed_resolution_mps=0.0,
                           gyro_noise_density_dps_rthz=0.0, gyro_bias_walk_dps_rts=0.0,
                           speed_scale_sigma=0.02)
    car = FakeCar()
    n_seeds = 3000  # std of std ~1.3 %
    scales, biases = [], []
    for seed in range(n_seeds):
        first, second = _run(config, seed=seed, n=2, car=car)
        assert first.speed_mps == second.speed_mps  # one scale factor per episode
        scales.append(first.speed_mps / car.speed)
        biases.append(first.yaw_rate_rps - car.yaw_rate)
    assert np.std(scales, ddof=1) == pytest.approx(config.speed_scale_sigma, rel=0.07)
    assert abs(np.mean(scales) - 1.0) < 5 * config.speed_scale_sigma / math.sqrt(n_seeds)
    assert np.std(biases, ddof=1) == pytest.approx(math.radians(config.gyro_bias_sigma_dps),
                                                    rel=0.07)


def test_quantisation_to_the_resolution():
    config = SensorsConfig()
    data = _columns(_run(config, n=200))
    speed_step = config.speed_resolution_mps
    steer_step = math.radians(config.steer_resolution_deg) / config.steering_ratio
    for column, step in ((data[:, 0], speed_step), (data[:, 4], steer_step)):
        units = column / step
        assert np.abs(units - np.round(units)).max() < 1e-6
        assert len(np.unique(column)) > 1


def test_perfect_returns_the_true_values_and_draws_nothing():
    rng = np.random.default_rng(5)
    before = rng.bit_generator.state
    sensors = VehicleSensors(SensorsConfig(perfect=True), 0.1, rng)
    car = FakeCar(speed=12.345, yaw_rate=-0.0123, accel=(-0.7, 1.234, 9.0), steer=-0.0456)
    for _ in range(3):
        assert sensors.sample(car) == VehicleSignals(12.345, -0.0123, -0.7, 1.234, -0.0456)
    assert rng.bit_generator.state == before


def test_config_validation():
    with pytest.raises(InvalidValue) as info:
        SensorsConfig(gyro_bias_sigma_dps=-0.1)
    assert info.value.key == "gyro_bias_sigma_dps"
    with pytest.raises(InvalidValue, match="accel_noise_density_mps2_rthz"):
        SensorsConfig(accel_noise_density_mps2_rthz=math.nan)
    with pytest.raises(InvalidValue, match="speed_scale_sigma"):
        SensorsConfig(speed_scale_sigma=0.5)
    with pytest.raises(InvalidValue, match="steering_ratio"):
        SensorsConfig(steering_ratio=0.0)
    with pytest.raises(ValueError, match="dt_s"):
        VehicleSensors(SensorsConfig(), 0.0, np.random.default_rng(0))


def test_scenario_sensors_table():
    assert parse_scenario(MINIMAL).sensors == SensorsConfig()
    scenario = parse_scenario(MINIMAL + "[sensors]\nperfect = true\ngyro_bias_sigma_dps = 1\n")
    assert scenario.sensors == SensorsConfig(perfect=True, gyro_bias_sigma_dps=1.0)
    with pytest.raises(ScenarioError) as info:
        parse_scenario(MINIMAL + "[sensors]\ngyro_bias_dps = 0.1\n")
    assert info.value.key == "sensors.gyro_bias_dps" and "unknown key" in str(info.value)
    with pytest.raises(ScenarioError) as info:
        parse_scenario(MINIMAL + "[sensors]\nspeed_noise_mps = -0.01\n")
    assert info.value.key == "sensors.speed_noise_mps" and ">= 0" in str(info.value)
    with pytest.raises(ScenarioError) as info:
        parse_scenario(MINIMAL + "[sensors]\nperfect = 1\n")
    assert info.value.key == "sensors.perfect"


def test_real_car_steady_turn(curve_world):
    """Perfect accelerometers read speed * yaw rate in a steady turn; noisy ones stay close."""
    car, dt_s = curve_world.car, curve_world.scenario.control_period_s
    perfect = VehicleSensors(SensorsConfig(perfect=True), dt_s, np.random.default_rng(0))
    noisy = VehicleSensors(SensorsConfig(), dt_s, np.random.default_rng(0))
    for _ in range(20):  # 2 s of a constant left steer: well past the transient
        curve_world.step(0.1, 0.05, dt_s)
        truth, reading = perfect.sample(car), noisy.sample(car)
        # The scalar signals; the radar's reading is lanekeep/sensing/radar.py's (None here).
        assert truth.radar is None and reading.radar is None
        scalars = [v for s in (truth, reading) for k, v in vars(s).items() if k != "radar"]
        assert all(math.isfinite(v) for v in scalars)
    assert truth.speed_mps == car.speed_mps() and truth.yaw_rate_rps == car.yaw_rate_rps()
    assert truth.steer_angle_rad == car.steer_angle_rad() > 0.0
    assert truth.yaw_rate_rps > 0.0 and truth.accel_lat_mps2 > 1.0  # left turn: + = left
    centripetal = truth.speed_mps * truth.yaw_rate_rps
    assert truth.accel_lat_mps2 == pytest.approx(centripetal, rel=0.01)
    assert abs(truth.accel_long_mps2) < 1.0
    assert reading.accel_lat_mps2 == pytest.approx(truth.accel_lat_mps2, abs=0.05)
    assert reading.speed_mps == pytest.approx(truth.speed_mps, rel=0.05)
