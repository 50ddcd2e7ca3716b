"""One page as the server the panel and the view draw on, and the server without the students' pages.
Made and used on the app's event thread.

The panel (:class:`~sandbox.app.panel.Panel`), the floor (:class:`~sandbox.app.view.scene.SceneView`)
and compare mode (:class:`~sandbox.app.view.partner.Comparison`) use of a server its ``gui``, its
``scene``, ``atomic()``, ``get_clients()`` and ``initial_camera``. viser gives each page the same GUI and
scene calls of its own (``client.gui``, ``client.scene``), sent to that page alone: :class:`OnePage`
is a page dressed as that server, so a student's panel and floor are the ones everybody knows, on
their page only. :class:`TeacherPages` is the shared server as the teacher's panel sees it: the pages
without a seat.
"""

from __future__ import annotations

from typing import Any, Callable


class OnePage:
    """``client`` as the server a panel is built on: what it draws goes to this page alone."""

    def __init__(self, client: Any):
        self.client = client
        self.gui = client.gui
        self.scene = client.scene
        #: A page has no initial camera of its own to set: its camera is set as it is.
        self.initial_camera = client.camera

    def atomic(self) -> Any:
        return self.client.atomic()

    def flush(self) -> None:
        self.client.flush()

    def get_clients(self) -> dict[int, Any]:
        return {self.client.client_id: self.client}

    def get_scene_serializer(self) -> Any:
        raise RuntimeError("recording is for the teacher's page; a student's world is not recorded here")


class TeacherPages:
    """The shared server, but ``get_clients()`` leaves out the pages that hold a seat (``seated(client_id)``)."""

    def __init__(self, server: Any, seated: Callable[[int], bool]):
        self._server, self._seated = server, seated

    def get_clients(self) -> dict[int, Any]:
        return {cid: client for cid, client in self._server.get_clients().items() if not self._seated(cid)}

    def __getattr__(self, name: str) -> Any:
        return getattr(self._server, name)
