"""Measure the front detectors' centre-line coefficient noise in the closed loop.

    MUJOCO_GL=egl .venv/bin/python tools/measure_detector_noise.py

The same as `python -m lanekeep.tuning.detector_noise`, which holds the command line and its
help.
"""

import sys

from lanekeep.tuning.detector_noise import main

if __name__ == "__main__":
    sys.exit(main())
