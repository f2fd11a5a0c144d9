"""What anti-aliasing does to the detectors, same pose for same pose (open loop).

    MUJOCO_GL=egl .venv/bin/python tools/measure_antialiasing.py --workers 2 --every 2

The same as `python -m lanekeep.tuning.antialiasing`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.antialiasing import main

if __name__ == "__main__":
    sys.exit(main())
