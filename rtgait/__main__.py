"""``python -m rtgait``: the same as the ``rtgait`` command."""

import sys

from rtgait.cli.main import main

sys.exit(main())
