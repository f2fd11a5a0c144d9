"""Contact sheet: every scenario's front and rear camera at the start and at mid-drive.

    MUJOCO_GL=egl .venv/bin/python tools/contact_sheet.py --out docs/contact_sheet.jpg \\
        [NAME_OR_TOML ...] [--tile 320x180] [--quality 80] [--real DIR]

The same as `python -m lanekeep.tuning.contact_sheet`, which holds the command line and its
help.
"""

import sys

from lanekeep.tuning.contact_sheet import main

if __name__ == "__main__":
    sys.exit(main())
