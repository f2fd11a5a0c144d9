"""Shade/sun luma ratio of the shipped shadow scenarios' front renders, measured exactly.

    MUJOCO_GL=egl .venv/bin/python tools/measure_shade.py [--out DIR]

The same as `python -m lanekeep.tuning.shade_ratio`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.shade_ratio import main

if __name__ == "__main__":
    sys.exit(main())
