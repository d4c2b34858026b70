"""``python -m tracking``: see :mod:`tracking.cli`."""
import sys

from .cli import main

sys.exit(main())
