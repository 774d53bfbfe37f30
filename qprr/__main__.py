"""``python -m qprr ...`` is the ``qprr`` command (useful from a source checkout)."""

import sys

from .cli import main

sys.exit(main())
