"""``python -m hybridship``: the command line, as the ``hybridship`` script runs it (for an
environment whose scripts folder is not on the PATH)."""

import sys

from .cli import main

sys.exit(main())
