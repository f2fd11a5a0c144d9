"""Choose LaneNet's decoding priors on the simulated validation split, never on the test sets.

    python tools/tune_lanenet_decode.py --data data/lanenet

The same as `python -m lanekeep.tuning.decode_priors`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.decode_priors import main

if __name__ == "__main__":
    sys.exit(main())
