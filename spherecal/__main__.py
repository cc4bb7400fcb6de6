"""``python -m spherecal``: the same as the ``spherecal`` command."""

import sys

from spherecal.cli import main

sys.exit(main())
