"""Measure the body roll compensation's constants (estimators/roll.py) on the tuning scenarios.

    MUJOCO_GL=egl .venv/bin/python tools/measure_roll_coupling.py [SCENARIO ...]

The same as `python -m lanekeep.tuning.roll_coupling`, which holds the command line and its
help.
"""

import sys

from lanekeep.tuning.roll_coupling import main

if __name__ == "__main__":
    sys.exit(main())
