"""The browser sandbox (``phototaxis serve``): a viser app on top of the engine.

Modules, one idea each:

- :mod:`.runner`   the simulation thread, its command queue and snapshots
- :mod:`.scene`    the top-down scene drawn from snapshots
- :mod:`.panel`    the control panel (run, shape, strategies, metrics, ...)
- :mod:`.learn`    the Learn text and its illustrations
- :mod:`.palette`  colours and pictures shared with recordings
- :mod:`.frames`   Pillow frames for GIF / MP4
- :mod:`.server`   the app and the ``serve`` subcommand
- :mod:`.live_bench`  speed with a real browser connected
"""

from __future__ import annotations

from typing import Any


def add_parser(sub: Any) -> Any:
    from .server import add_parser as _add

    return _add(sub)


__all__ = ["add_parser"]
