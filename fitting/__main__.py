"""``python -m fitting``: see :mod:`fitting.cli`."""
import sys

from .cli import main

sys.exit(main())
