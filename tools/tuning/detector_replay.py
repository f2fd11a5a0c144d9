"""Replay recorded camera frames through the classical detectors and score them.

    MUJOCO_GL=egl .venv/bin/python tools/tuning/detector_replay.py record SCENARIO DIR
    .venv/bin/python tools/tuning/detector_replay.py score DIR

The same as `python -m lanekeep.tuning.detector_replay`, which holds the command line and its
help.
"""

import sys

from lanekeep.tuning.detector_replay import main

if __name__ == "__main__":
    sys.exit(main())
