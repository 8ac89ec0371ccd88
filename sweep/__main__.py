"""``python -m sweep``: the same as the ``sweep`` command."""
import sys

from .cli import main

sys.exit(main())
