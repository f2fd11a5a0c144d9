"""lanekeep: a headless closed-loop lane-keeping testbed on MuJoCo.

MuJoCo's offscreen renderer needs an OpenGL backend chosen before `mujoco` is imported; on a
headless machine only EGL works, so it is the default unless the user already chose one.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
