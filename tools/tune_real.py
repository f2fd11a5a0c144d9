"""Score the detectors on labelled real frames (TuSimple rule), for tuning and validation.

    .venv/bin/python tools/tune_real.py ../shared/real/tusimple_dev [--detector lanenet]

The same as `python -m lanekeep.tuning.real_accuracy`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.real_accuracy import main

if __name__ == "__main__":
    sys.exit(main())
