"""``python -m herman2019 ...``: the ``herman2019`` command (:mod:`herman2019.cli`)."""
import sys

from herman2019.cli import main

sys.exit(main())
