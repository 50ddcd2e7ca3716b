"""viser's button icons, read from its icon archive opened once.

viser 1.1 reads each icon with ``svg_from_icon``, which opens and indexes its
archive of about 5,000 icons for every new icon name: 0.07 s each, 1.3 s for
the panel's 18 icons, every time a server starts. :func:`read_icons_once`
puts in its place a reader with the same answers that indexes the archive
once per process. If viser's layout changes, it leaves viser as it is.
"""

from __future__ import annotations

import functools
import threading
import zipfile

_lock = threading.Lock()


@functools.cache
def _archive(path: str) -> zipfile.ZipFile:
    return zipfile.ZipFile(path)


def _reader(path: str):
    @functools.cache
    def svg_from_icon(icon_name: str) -> str:
        assert isinstance(icon_name, str)
        with _lock:  # one open archive, read from the server's threads
            return _archive(path).read(f"{icon_name}.svg").decode("utf-8")

    return svg_from_icon


def read_icons_once() -> bool:
    """Make viser read its icons from an archive opened once; True if it did."""
    try:
        from viser import _gui_api, _gui_handles, _icons
    except ImportError:
        return False
    if getattr(_gui_api.svg_from_icon, "reads_once", False):
        return True
    path = _icons.ICONS_DIR / "tabler-icons.zip"
    if not path.is_file() or not all(hasattr(m, "svg_from_icon") for m in (_gui_api, _gui_handles, _icons)):
        return False
    reader = _reader(str(path))
    reader.reads_once, reader.viser_reader = True, _icons.svg_from_icon
    for module in (_gui_api, _gui_handles, _icons):
        module.svg_from_icon = reader
    return True
