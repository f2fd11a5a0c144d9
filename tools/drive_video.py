"""A closed-loop drive's front frames as a video with its camera file (for `lanekeep detect`).

The same as `python -m lanekeep.tuning.drive_video`, which holds the command line and its help.
"""

import sys

from lanekeep.tuning.drive_video import main

if __name__ == "__main__":
    sys.exit(main())
