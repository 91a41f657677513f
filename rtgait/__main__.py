"""``python -m rtgait``: the same as the ``rtgait`` command."""

import sys

from rtgait.cli import main

sys.exit(main())
