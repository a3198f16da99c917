"""``python -m hybridship``: the command line, as the ``hybridship`` script runs it (for an
environment whose scripts folder is not on the PATH)."""

import sys

from .cli import main

if __name__ == "__main__":  # importing the module (an API listing, a doc build) must not run the CLI
    sys.exit(main())
