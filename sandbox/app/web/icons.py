"""viser's button icons, read from its icon archive opened once.
Read from the main thread and the app's event thread (one archive, under a lock).

viser 1.1 reads each icon with ``svg_from_icon``, which opens and indexes its
archive of about 5,000 icons for every new icon name: 0.07 s each, 1.3 s for
the panel's 18 icons, every time a server starts. :func:`read_icons_once`
puts in its place a reader with the same answers that indexes the archive
once per process (through :mod:`sandbox.app.web.viser_seam`). If viser's layout
changes, it leaves viser as it is.

The reader serves every viser server in the process, on whichever thread adds a control with an icon.
"""

from __future__ import annotations

import functools
import threading
import zipfile

from sandbox.app.web import viser_seam

# Shared by the threads that add controls with icons: the main thread (building the panel) and the app's
# event thread (a folder that adds a button later); the archive is one open file for the whole process.
_lock = threading.Lock()


@functools.cache
def _archive(path: str) -> zipfile.ZipFile:
    return zipfile.ZipFile(path)


def _reader(path: str):
    @functools.cache
    def svg_from_icon(icon_name: str) -> str:
        assert isinstance(icon_name, str)
        with _lock:
            return _archive(path).read(f"{icon_name}.svg").decode("utf-8")

    return svg_from_icon


def read_icons_once() -> bool:
    """Make viser read its icons from an archive opened once; True if it did."""
    viser_reader = viser_seam.icon_reader()
    if getattr(viser_reader, "reads_once", False):
        return True
    path = viser_seam.icon_archive()
    if viser_reader is None or path is None:
        return False
    reader = _reader(str(path))
    reader.reads_once, reader.viser_reader = True, viser_reader
    return viser_seam.read_icons_with(reader)
