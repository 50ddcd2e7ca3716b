"""A folder of the panel opened on one page, and brought into view: what the server asks of the page
that pressed a button whose answer is in another folder (the Result folder after *Run to the end*).
The script runs in the page; the app's event thread sends it.

The panel is one for every page, and viser 1.1.1 opens a folder only when it builds it
(``expand_by_default``), for every page at once. So the server sends the one page a line of script
(viser's ``RunJavascriptMessage``, through :func:`sandbox.app.web.viser_seam.send_to`: never into the
backlog a new page replays) that calls the layout script's ``window.__phototaxisOpenFolder``
(:mod:`sandbox.app.web.page_layout`): it opens the phone's drawer if closed, the folder if closed, and
scrolls the folder's title to the top of the panel. Other pages keep their panel as it is. The line is
``page/open.js``; it relies on nothing in viser's client but what every page script does
(:data:`sandbox.app.web.client_seam.RUNS_SCRIPTS`)."""

from __future__ import annotations

import logging
from typing import Any

from sandbox.app.web import viser_seam
from sandbox.app.web.client_seam import script

log = logging.getLogger("sandbox.app.web.page_open")


def open_folder_js(title: str, inside: str) -> str:
    """The script that opens the folder titled ``title`` on a page; ``inside``: a button's label in it,
    shown once the folder is open."""
    return script("open.js", title=title, inside=inside)


def open_folder(client: Any, title: str, inside: str) -> None:
    """Open the folder ``title`` on ``client``'s page only (nothing for no page, or one that left)."""
    if client is None:
        return
    try:
        viser_seam.send_to(client, viser_seam.messages.RunJavascriptMessage(source=open_folder_js(title, inside)))
    except Exception as exc:  # noqa: BLE001 - the page has left: nothing to open
        log.debug("could not open %s on page %s: %s", title, getattr(client, "client_id", "?"), exc)
