"""``python -m floewave run ...`` (see :mod:`floewave.cli`)."""
import sys

from .cli import main

sys.exit(main())
