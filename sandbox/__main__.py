"""``python -m sandbox`` is the ``phototaxis`` command."""

import sys

from .cli import main

sys.exit(main())
