"""lanekeep: a headless closed-loop lane-keeping testbed on MuJoCo.

The tree is the architecture. One subpackage per concern, lowest layer first; a subpackage
imports only from lower layers, packages on one layer never import each other, and nothing
imports `cli` (tests/project/test_layers.py enforces it):

    0  core        config reading, plug-in loading, stop signals, timing, progress, workers,
                   files, the vehicle-signal and step types;  mjcf (the car's MJCF, data)
    1  geometry    road (Frenet), road meshes, marking layout, pinhole camera, lens, car specs
    2  detectors   lane detectors (frames -> LaneEstimate);  realcam (real cameras, photos);
                   traffic (IDM car following, MOBIL lane changes, lane-change paths:
                   pure maths on the road's Frenet frame)
    3  estimators  Kalman trackers, MMAE, the closed loop's estimator and its settings
    4  scenario    the scenario schema (frozen dataclasses from TOML), shipped scenarios
    5  world       the MjSpec world: road, paint, props, traffic, lighting, the car
    6  sensing     cameras and renders, lens and weather effects, vehicle sensors, Simulator
    7  control     the Controller interface, PID (paper 001 eq. 9), Stanley, registry
    8  driver      what the car runs: Driver.step(Observation) -> (Command, Belief)
    9  scoring     truth (computed once a step), StepScorer, metrics, departures, criteria
    10 report      rerun recording, plots, JSON, JUnit, tables, one palette
    11 loop        Episode, the runner;                       evaluation (AP, IoU, datasets)
    12 sweep       grids of episodes;  envs (dm_env, Gymnasium);  tuning (tools' library)
    13 cli         thin: parse, call one library function, print, exit code

The car's side (detectors, estimators, control, driver) never imports the world, sensing,
scoring, the loop, the recorder, MuJoCo or dm_control: perception, estimation and control see
camera frames and vehicle signals only, by construction, and only scoring and report read the
simulator's truth.
No private name crosses a module.

MuJoCo's offscreen renderer needs an OpenGL backend chosen before `mujoco` is imported; on a
headless machine only EGL works, so it is the default unless the user already chose one.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

# Every numeric library capped at AVX2 before it loads, so that two machines give the same
# numbers (lanekeep/core/reproducibility.py; LANEKEEP_PIN=0 opts out).
from lanekeep.core import reproducibility as _reproducibility  # noqa: E402

_reproducibility.pin_kernels()
_reproducibility.warn_if_loaded_before_pin()

__version__ = "0.1.0"

# The repository keeps detectors/, estimators/ and mjcf/ beside this folder; an install maps
# them into this namespace (pyproject's package-dir). When this package is the checkout's own
# folder (`python -m lanekeep.cli` from a clone's root, which puts the clone first on
# sys.path), those three, and only those, are found beside it, as the install would place them
# (lanekeep/core/checkout.py); the clone's other folders (tools, tests, docs) stay outside.
from lanekeep.core.checkout import map_checkout_folders as _map_checkout_folders  # noqa: E402

_map_checkout_folders(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# gymnasium.make("lanekeep/LaneKeep-v0") after `import lanekeep`, gymnasium not imported here.
from lanekeep.envs import gym_registration as _gym_registration  # noqa: E402

_gym_registration.install()
