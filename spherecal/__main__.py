"""``python -m spherecal``: the same as the ``spherecal`` command."""

import sys

from spherecal.cli import main

if __name__ == "__main__":  # not when a spawned worker (a Dask cluster's) imports the main module
    sys.exit(main())
