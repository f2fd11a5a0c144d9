"""Replay one drive's estimator inputs through the estimator with other settings.

    MUJOCO_GL=egl .venv/bin/python tools/replay_estimation.py record DIR [SCENARIO ...]
    .venv/bin/python tools/replay_estimation.py compare DIR reference_std_m=0.05,0.03

The same as `python -m lanekeep.tuning.replay`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.replay import main

if __name__ == "__main__":
    sys.exit(main())
