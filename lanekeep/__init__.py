"""lanekeep: a headless closed-loop lane-keeping testbed on MuJoCo.

MuJoCo's offscreen renderer needs an OpenGL backend chosen before `mujoco` is imported; on a
headless machine only EGL works, so it is the default unless the user already chose one.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

# gymnasium.make("lanekeep/LaneKeep-v0") after `import lanekeep`, gymnasium not imported here.
from lanekeep import gym_registration as _gym_registration  # noqa: E402

_gym_registration.install()
