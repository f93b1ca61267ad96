"""``python -m mbsynth.cli``: the ``mbsynth`` command."""

import sys

from . import main

sys.exit(main())
