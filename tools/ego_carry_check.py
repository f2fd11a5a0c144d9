"""How well the car's own motion carries a lane from one frame to the next (a coasting track).

    MUJOCO_GL=egl .venv/bin/python tools/ego_carry_check.py [SCENARIO ...] [--seeds 3]

The same as `python -m lanekeep.tuning.ego_carry`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.ego_carry import main

if __name__ == "__main__":
    sys.exit(main())
