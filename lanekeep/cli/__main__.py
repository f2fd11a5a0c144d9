"""`python -m lanekeep.cli`: the same as the `lanekeep` command."""

import sys

from lanekeep.cli.main import main

sys.exit(main())
