"""Calibrate the shipped scenarios' fused-RMSE limits on tuning seeds.

    lanekeep bench --seed 1000 --seeds 5 --json tuning.json
    python tools/calibrate_criteria.py tuning.json            # the table only
    python tools/calibrate_criteria.py tuning.json --write    # and rewrite each [criteria]

The same as `python -m lanekeep.tuning.criteria_calibration`, which holds the command line and
its help.
"""

import sys

from lanekeep.tuning.criteria_calibration import main

if __name__ == "__main__":
    sys.exit(main())
