"""Compare values of one `[estimation]` key in the closed loop, on the tuning scenarios.

    MUJOCO_GL=egl .venv/bin/python tools/compare_estimation.py output=select,fused

The same as `python -m lanekeep.tuning.estimation`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.estimation import main

if __name__ == "__main__":
    sys.exit(main())
