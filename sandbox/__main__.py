"""``python -m sandbox`` is the ``phototaxis`` command."""

import sys

from sandbox.commands import main

sys.exit(main())
