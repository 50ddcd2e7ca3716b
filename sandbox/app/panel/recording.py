"""The Record folder: capture the scene and download it as one HTML file
that replays without a server. Runs on the app's event thread.

Runs on the app's event thread, which owns the recorder."""

from __future__ import annotations

import datetime as _dt
import re
import time
from typing import Any

import viser

from sandbox.app.view.scene import add_floor_legend
from sandbox.app.world.snapshot import Snapshot, running_case

MAX_RECORD_SECONDS = 120.0


def recording_name(snap: Snapshot | None, when: _dt.datetime) -> str:
    """The downloaded file's name: what runs (the paper's case, or the goal's name and its
    strategies) and when, so that a class's recordings do not all overwrite one file."""
    if snap is None:
        what = "run"
    else:
        what = running_case(snap.shape_name, snap.strategies, snap.family) or "-".join(
            [snap.shape_name.rsplit(".", 1)[0], *sorted(k for k, v in snap.strategies.items() if v > 0)])
    what = re.sub(r"[^A-Za-z0-9_]+", "-", what).strip("-")[:60] or "run"
    return f"phototaxis-{what}-{when:%Y-%m-%d-%H%M}.html"


class RecordFolder:
    def __init__(self, gui: Any, server: Any, runner: Any):
        self.gui, self.server, self.runner = gui, server, runner
        self.recorder: Any = None
        self._finished_html: str | None = None
        self._started = self._last_time = 0.0
        self._snap: Snapshot | None = None
        self._floor_legend: Any = None

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Record", expand_by_default=False):
            gui.add_markdown("Capture the run and download it as one HTML file that replays in any browser, "
                             f"no server needed (at most {MAX_RECORD_SECONDS:.0f} s).")
            self.button = gui.add_button("Start recording", icon=viser.Icon.PLAYER_RECORD)
            self.status = gui.add_markdown("")

        @self.button.on_click
        def _(event: viser.GuiEvent) -> None:
            if self.idle:
                self.start()
                return
            html = self.stop()
            event.client.send_file_download(recording_name(self._snap, _dt.datetime.now()), html.encode("utf-8"),
                                            save_immediately=True)

    @property
    def idle(self) -> bool:
        """Neither recording nor holding a finished recording to download."""
        return self.recorder is None and self._finished_html is None

    def update(self, snap: Snapshot) -> None:
        self._snap = snap
        if self.recorder is not None:
            self.status.content = f"Recording: {time.perf_counter() - self._started:.0f} s"

    def start(self) -> None:
        # The replay has no panel: its legend goes on the floor beside the arena while recording.
        self._floor_legend = add_floor_legend(self.server.scene, self.runner.latest.world_config)
        self.recorder = self.server.get_scene_serializer()
        self._started = self._last_time = time.perf_counter()
        self.button.label = "Stop and download"
        self.button.icon = viser.Icon.PLAYER_STOP
        self.status.content = "Recording..."

    def stop(self) -> str:
        """Finish the recording; returns it as standalone HTML."""
        recorder, self.recorder = self.recorder, None
        html, self._finished_html = self._finished_html, None
        if recorder is not None:
            html = recorder.as_html(dark_mode=True)
        self._remove_floor_legend()
        self.button.label = "Start recording"
        self.button.icon = viser.Icon.PLAYER_RECORD
        self.status.content = ""
        return html or ""

    def _remove_floor_legend(self) -> None:
        legend, self._floor_legend = self._floor_legend, None
        if legend is not None:
            legend.remove()

    def on_frame_drawn(self) -> None:
        """Called after each frame is drawn: advance the recording clock."""
        if self.recorder is None:
            return
        now = time.perf_counter()
        self.recorder.insert_sleep(now - self._last_time)
        self._last_time = now
        if now - self._started <= MAX_RECORD_SECONDS:
            return
        recorder, self.recorder = self.recorder, None
        self._finished_html = recorder.as_html(dark_mode=True)
        self._remove_floor_legend()
        self.status.content = f"Stopped at {MAX_RECORD_SECONDS:.0f} s: press the button to download."
        self.button.label = "Download recording"
        self.button.icon = viser.Icon.DOWNLOAD
