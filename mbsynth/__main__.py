"""``python -m mbsynth``: the ``mbsynth`` command."""

import sys

from .cli import main

sys.exit(main())
