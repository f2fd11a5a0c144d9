"""Why the fused output beats or loses to a model: per-model bias, spread, MMAE weight, and
what the reference can see of them.

    MUJOCO_GL=egl .venv/bin/python tools/trace_estimation.py night [--output fused]

The same as `python -m lanekeep.tuning.trace`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.trace import main

if __name__ == "__main__":
    sys.exit(main())
