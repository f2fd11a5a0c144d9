"""lanekeep: a headless closed-loop lane-keeping testbed on MuJoCo.

MuJoCo's offscreen renderer needs an OpenGL backend chosen before `mujoco` is imported; on a
headless machine only EGL works, so it is the default unless the user already chose one.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

# The repository keeps detectors/, estimators/ and mjcf/ beside this folder; an install maps
# them into this namespace (pyproject's package-dir). When this package is the checkout's own
# folder (`python -m lanekeep.cli` from a clone's root, which puts the clone first on
# sys.path), its subpackages are looked up beside it too, as the install would place them.
_checkout = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if os.path.isfile(os.path.join(_checkout, "pyproject.toml")) and os.path.isfile(
        os.path.join(_checkout, "detectors", "registry.py")):
    __path__.append(_checkout)  # noqa: F821 - a package's own __path__

# gymnasium.make("lanekeep/LaneKeep-v0") after `import lanekeep`, gymnasium not imported here.
from lanekeep.envs import gym_registration as _gym_registration  # noqa: E402

_gym_registration.install()
