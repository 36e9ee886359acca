"""``python -m gausspp.cli``: the ``gausspp`` command."""

import sys

from . import main

sys.exit(main())
