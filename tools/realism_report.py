"""Realism report: the same image statistics for rendered frames and real photos, side by side.

    MUJOCO_GL=egl .venv/bin/python tools/realism_report.py --real ../shared/real \\
        [--scenarios clear_straight night ...] [--at S] [--out report.md] [--json report.json]

The same as `python -m lanekeep.tuning.realism_report`, which holds the command line and its
help.
"""

import sys

from lanekeep.tuning.realism_report import main

if __name__ == "__main__":
    sys.exit(main())
