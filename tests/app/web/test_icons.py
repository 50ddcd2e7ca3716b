"""viser's icons read from an archive opened once (sandbox/app/web/icons.py) are the icons viser reads."""

from __future__ import annotations

from sandbox.app.web.icons import read_icons_once


def test_icons_read_once_are_visers_own_and_indexed_once():
    from viser import _gui_api, _gui_handles

    assert read_icons_once() and read_icons_once()  # a second call keeps the first reader
    reader = _gui_api.svg_from_icon
    assert _gui_handles.svg_from_icon is reader
    names = ["player-play", "player-pause", "refresh", "download", "upload", "pencil", "trash", "check"]
    mine = [reader(name) for name in names]
    assert mine == [reader.viser_reader(name) for name in names]
    assert all(svg.lstrip().startswith("<svg") for svg in mine)
    from sandbox.app.web.icons import _archive

    assert _archive.cache_info().currsize == 1  # indexed once; viser's own reader: once per new name
