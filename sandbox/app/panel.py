"""The control panel: run controls, goal shape (pick, draw, upload, download),
strategies, parameters, metrics, inspector, recording and the Learn text.

Every callback here runs on a viser thread. None of them touches the
simulation: they post commands to the :class:`~sandbox.app.runner.Runner`.
The parameter folders are generated from the engine's declaration
(:func:`sandbox.config.params`).
"""

from __future__ import annotations

import csv
import functools
import io
import tempfile
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import viser
import viser.uplot

from sandbox.model.config import STRATEGY_DEFAULTS, Config, params
from sandbox.model.metrics import SampleWriter
from sandbox.model.robots import PHOTOCELLS
from sandbox.shapes import ShapeError, builtin_shape_names, load_polygon, polygon_to_text, shape_vertices, validate_polygon
from sandbox.model.simulation import Simulation
from sandbox.app import learn
from sandbox.app.runner import FASTEST, Snapshot, update_config_and_report

if TYPE_CHECKING:  # pragma: no cover
    from sandbox.app.server import App

#: Parameters that get their own controls elsewhere (or make no sense live).
NOT_IN_PARAMETER_FOLDERS = {"shape", "flare", "switch", "no_corners", "steps"}
GROUP_TITLES = {"bodies": "Population and bodies", "robot": "Robot: gains and energy", "lights": "Light grid",
                "controller": "Controller cycle", "arena": "Arena", "run": "Run", "physics": "Physics engine",
                "model": "Model: the authors' program or the paper's text"}
MODEL_HELP = ("The paper's text and the authors' released program differ in about a dozen places; the "
              "program produced the paper's tables. **profile** sets all of the values below at once "
              "(on reset); each can then be changed on its own.")
CUSTOM_SHAPE = "(drawn or uploaded)"
STRATEGY_LABELS = {"flare": "Flare", "switch": "Switch to circle", "no_corners": "No corners"}
PANEL_HZ = 6.0  # how often read-outs and charts refresh
MAX_RECORD_SECONDS = 120.0


def notify_error(client: Any, title: str, body: str) -> None:
    if client is not None:
        client.add_notification(title, body, color="red", auto_close_seconds=10.0)


def notify(client: Any, title: str, body: str, color: str = "blue") -> None:
    if client is not None:
        client.add_notification(title, body, color=color, auto_close_seconds=5.0)


def floor_point(origin: tuple, direction: tuple) -> tuple[float, float] | None:
    """Where a click ray meets the floor (z = 0), or None if it misses."""
    o, d = np.asarray(origin, float), np.asarray(direction, float)
    if abs(d[2]) < 1e-9:
        return None
    t = -o[2] / d[2]
    if t < 0:
        return None
    p = o + t * d
    return float(p[0]), float(p[1])


class Panel:
    """Builds the GUI on ``app.server`` and keeps its read-outs current."""

    def __init__(self, app: "App"):
        self.app = app
        self.runner = app.runner
        self.gui = app.server.gui
        self.draw_points: list[tuple[float, float]] = []
        self.drawing = False
        self._last_refresh = 0.0
        self._lock = threading.Lock()
        self.recorder: Any = None
        self._record_started = 0.0
        self._last_record_time = 0.0
        self._pending: set[str] = set()
        #: The settings in force, as the simulation last reported them (pending values included).
        self._settings: Config = self.runner.latest.config
        self._shape_picked_at = 0.0
        snap = self.runner.latest
        self._build_run(snap)
        self._build_shape(snap)
        self._build_strategies(snap)
        self._build_metrics(snap)
        self._build_inspector()
        self._build_record()
        self._build_parameters(snap)
        self._build_learn()
        app.server.scene.on_click()(self._on_scene_click)

    # ================================================================ run
    def _build_run(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Run"):
            self.play = gui.add_button("Pause" if self.runner.playing else "Play",
                                       icon=viser.Icon.PLAYER_PAUSE if self.runner.playing else viser.Icon.PLAYER_PLAY,
                                       hint="Start or stop the simulation")
            self.step_button = gui.add_button("Step", icon=viser.Icon.PLAYER_TRACK_NEXT,
                                              hint="Advance one world step (pauses first)")
            self.reset_same = gui.add_button("Reset (same seed)", icon=viser.Icon.REFRESH,
                                             hint="Rebuild the world with the same seed: the same run again")
            self.reset_new = gui.add_button("Reset (new seed)", icon=viser.Icon.DICE,
                                            hint="Rebuild the world with a new random seed")
            self.speed = gui.add_slider("Steps per frame", 1, FASTEST, 1, self.runner.steps_per_frame,
                                        hint=f"Speed: world steps simulated between two pictures; {FASTEST}: as "
                                             "fast as the machine can, the pictures still at the frame rate")
            self.show_field = gui.add_checkbox("Show sensed light", False,
                                               hint="Show the luminosity field the robots sense, as a heat map, "
                                                    "instead of the light grid")
            self.status = gui.add_markdown(self._status_text(snap))

        @self.play.on_click
        def _(event: viser.GuiEvent) -> None:
            self.runner.set_playing(not self.runner.playing)
            self._sync_play_button()

        @self.step_button.on_click
        def _(event: viser.GuiEvent) -> None:
            self.runner.set_playing(False)
            self._sync_play_button()
            self.runner.step_once(1)

        @self.reset_same.on_click
        def _(event: viser.GuiEvent) -> None:
            self.runner.reset(None)
            self._reset_done(event.client)

        @self.reset_new.on_click
        def _(event: viser.GuiEvent) -> None:
            self.runner.reset(int(np.random.default_rng().integers(0, 2**31 - 1)))
            self._reset_done(event.client)

        @self.speed.on_update
        def _(event: viser.GuiEvent) -> None:
            self.runner.set_speed(int(self.speed.value))

        @self.show_field.on_update
        def _(event: viser.GuiEvent) -> None:
            self.runner.want_field = bool(self.show_field.value)  # the next snapshots carry the field
            self.app.view.set_show_field(self.show_field.value, self.runner.latest)

    def _reset_done(self, client: Any) -> None:
        self.runner.select(None)
        if self._pending:
            notify(client, "Reset", "Applied: " + ", ".join(sorted(self._pending)), "green")
        self._pending.clear()
        self.pending.content = ""

    def _sync_play_button(self) -> None:
        playing = self.runner.playing
        self.play.label = "Pause" if playing else "Play"
        self.play.icon = viser.Icon.PLAYER_PAUSE if playing else viser.Icon.PLAYER_PLAY

    def _status_text(self, snap: Snapshot) -> str:
        cfg = snap.world_config
        return (f"**Step** {snap.step:,} &nbsp; **time** {snap.time:,.1f} s  \n"
                f"**Phase** {snap.phase} &nbsp; **cycle** {snap.cycle}  \n"
                f"**Seed** {snap.seed} &nbsp; {cfg.robots} robots, {cfg.boxes} boxes, goal *{snap.shape_name}*  \n"
                + (f"**Speed** {self.runner.steps_per_second():,.0f} steps/s "
                   f"({self.runner.steps_per_second() * cfg.dt:,.1f}x real time), "
                   f"{self.runner.frames_per_second():,.0f} frames/s" if snap.playing else "**Paused**"))

    # ============================================================== shape
    def _build_shape(self, snap: Snapshot) -> None:
        gui = self.gui
        # A drawn or uploaded goal shows as CUSTOM_SHAPE, so picking a
        # built-in shape afterwards is always a change.
        names = [*builtin_shape_names(), CUSTOM_SHAPE]
        current = snap.shape_name if snap.shape_name in names else CUSTOM_SHAPE
        with gui.add_folder("Goal shape"):
            self.shape = gui.add_dropdown("Shape", tuple(names), initial_value=current,
                                          hint="circle, or a polygon file from shapes/")
            with gui.add_folder("Draw", expand_by_default=False):
                self.draw_help = gui.add_markdown(
                    "Press **Start drawing**, then click points on the floor; the preview line follows. "
                    "The shape is centred and scaled to the boxes' area when used.")
                self.draw_toggle = gui.add_button("Start drawing", icon=viser.Icon.PENCIL)
                self.draw_undo = gui.add_button("Undo last point", icon=viser.Icon.ARROW_BACK_UP, disabled=True)
                self.draw_close = gui.add_button("Close and use", icon=viser.Icon.CHECK, disabled=True)
                self.draw_clear = gui.add_button("Clear", icon=viser.Icon.TRASH, disabled=True)
            self.upload = gui.add_upload_button(
                "Upload polygon file", icon=viser.Icon.UPLOAD,
                hint="Plain text x y per line, GeoJSON, WKT, JSON [[x, y], ...] or SVG")
            self.download_shape = gui.add_button("Download shape", icon=viser.Icon.DOWNLOAD,
                                                 hint="The current goal as a polygon file for --shape")

        @self.shape.on_update
        def _(event: viser.GuiEvent) -> None:
            name = self.shape.value
            self._shape_picked_at = time.perf_counter()
            if name == self.runner.latest.shape_name or name not in builtin_shape_names():
                return
            try:
                vertices = shape_vertices(name)
            except ShapeError as exc:
                notify_error(event.client, "Shape not used", str(exc))
                return
            self.runner.set_shape(vertices, name)

        @self.draw_toggle.on_click
        def _(event: viser.GuiEvent) -> None:
            self.drawing = not self.drawing
            self._sync_draw_buttons()

        @self.draw_undo.on_click
        def _(event: viser.GuiEvent) -> None:
            if self.draw_points:
                self.draw_points.pop()
            self._sync_draw_buttons()

        @self.draw_clear.on_click
        def _(event: viser.GuiEvent) -> None:
            self.draw_points.clear()
            self._sync_draw_buttons()

        @self.draw_close.on_click
        def _(event: viser.GuiEvent) -> None:
            try:
                vertices = validate_polygon(self.draw_points, "drawn shape")
            except ShapeError as exc:
                notify_error(event.client, "Shape not used", str(exc))
                return
            self.runner.set_shape(vertices, "drawn")
            self.draw_points.clear()
            self.drawing = False
            self._sync_draw_buttons()
            notify(event.client, "Goal changed", f"Using the drawn shape ({len(vertices)} vertices).", "green")

        @self.upload.on_upload
        def _(event: viser.GuiEvent) -> None:
            uploaded = self.upload.value
            self.use_shape_file(uploaded.name or "upload.txt", uploaded.content, event.client)

        @self.download_shape.on_click
        def _(event: viser.GuiEvent) -> None:
            snap = self.runner.latest
            name = snap.shape_name or "shape"
            vertices = snap.goal_vertices if snap.goal_vertices is not None else snap.goal_outline
            comment = (f"phototaxis goal shape '{name}' in arena coordinates (metres)\n"
                       "use with: phototaxis --shape FILE")
            if snap.goal_vertices is None:
                comment += f"\nthe circle, as a {len(vertices)}-gon"
            text = polygon_to_text(vertices, comment)
            stem = Path(name).stem.replace(" ", "-") or "shape"
            event.client.send_file_download(f"{stem}.txt", text.encode("utf-8"), save_immediately=True)

    def use_shape_file(self, filename: str, content: bytes, client: Any) -> bool:
        """Validate an uploaded polygon file with the engine's loader; use it or say why not."""
        safe = Path(filename).name or "upload.txt"
        try:
            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / safe
                path.write_bytes(content)
                vertices = load_polygon(path)
        except ShapeError as exc:
            notify_error(client, "Shape not used", str(exc))
            return False
        except OSError as exc:
            notify_error(client, "Shape not used", f"{safe}: cannot read the upload ({exc})")
            return False
        self.runner.set_shape(vertices, safe)
        notify(client, "Goal changed", f"Using {safe} ({len(vertices)} vertices).", "green")
        return True

    def _sync_draw_buttons(self) -> None:
        n = len(self.draw_points)
        self.draw_toggle.label = "Stop drawing" if self.drawing else "Start drawing"
        self.draw_undo.disabled = n == 0
        self.draw_clear.disabled = n == 0
        self.draw_close.disabled = n < 3
        self.app.view.set_draw_points(self.draw_points)

    def _on_scene_click(self, event: Any) -> None:
        point = floor_point(event.ray_origin, event.ray_direction)
        if point is None:
            return
        if self.drawing:
            self.draw_points.append(point)
            self._sync_draw_buttons()
            return
        # Inspect: the nearest robot within a couple of body lengths.
        snap = self.runner.latest
        if len(snap.robot_positions) == 0:
            return
        d = np.hypot(*(snap.robot_positions - np.asarray(point)).T)
        i = int(np.argmin(d))
        if d[i] <= max(1.5, 6 * snap.world_config.robot_radius):
            self.runner.select(i)
            self.inspect_help.content = f"Following robot **{i}** (click another, or stop)."
            self.stop_follow.disabled = False

    # ========================================================= strategies
    def _build_strategies(self, snap: Snapshot) -> None:
        gui = self.gui
        self.strategy_controls: dict[str, tuple[Any, Any]] = {}
        with gui.add_folder("Strategies"):
            gui.add_markdown("Changes reach the running simulation at the next controller update; no reset.")
            for name in ("flare", "switch", "no_corners"):
                p = next(q for q in params() if q.name == name)
                value = getattr(snap.config, name)
                on = gui.add_checkbox(STRATEGY_LABELS[name], value > 0, hint=p.help)
                high = 4.0 if name == "flare" else 1.0
                amount = gui.add_slider(f"{STRATEGY_LABELS[name]} amount", 0.05, high, 0.05,
                                        float(value if value > 0 else STRATEGY_DEFAULTS[name]), hint=p.help)
                self.strategy_controls[name] = (on, amount)
                on.on_update(lambda event, n=name: self._strategy_changed(n, event.client))
                amount.on_update(lambda event, n=name: self._strategy_changed(n, event.client))

    def _strategy_changed(self, name: str, client: Any) -> None:
        on, amount = self.strategy_controls[name]
        value = float(amount.value) if on.value else 0.0

        def failed(exc: BaseException) -> None:
            notify_error(client, "Strategy not changed", str(exc))

        self.runner.post(functools.partial(Simulation.set_strategies, **{name: value}), on_error=failed)

    # ============================================================ metrics
    def _build_metrics(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Metrics"):
            self.metrics_text = gui.add_markdown(self._metrics_text(snap))
            x = np.array([0.0, 0.0])
            # x is the world step (not a date: "time": False below).
            common = dict(height=130, padding=(8, 12, 0, 0), legend={"show": False})
            self.chart_goal = gui.add_uplot(
                (x, x), ({"label": "step"}, {"label": "in goal", "stroke": "#ff5ca8", "width": 2}),
                title="Boxes in goal (fraction) vs step", scales={"x": {"time": False}, "y": {"range": [0, 1]}}, **common)
            self.chart_dist = gui.add_uplot(
                (x, x), ({"label": "step"}, {"label": "stray distance", "stroke": "#40c8ff", "width": 2}),
                title="Mean distance of stray boxes (m)", scales={"x": {"time": False}}, **common)
            self.chart_charged = gui.add_uplot(
                (x, x), ({"label": "step"}, {"label": "charged", "stroke": "#2ecc40", "width": 2}),
                title="Charged robots", scales={"x": {"time": False}}, **common)
            self.download_csv = gui.add_button("Download CSV", icon=viser.Icon.FILE_SPREADSHEET,
                                               hint="The metrics time series of this run")

        @self.download_csv.on_click
        def _(event: viser.GuiEvent) -> None:
            event.client.send_file_download("phototaxis-metrics.csv", self.metrics_csv().encode("utf-8"),
                                            save_immediately=True)

    def metrics_csv(self) -> str:
        out = io.StringIO()
        dt = self.runner.latest.world_config.dt
        writer = SampleWriter(out, trailing=("time",))
        for s in self.runner.series():
            writer.write(s, time=round(s.step * dt, 4))
        return out.getvalue()

    def _metrics_text(self, snap: Snapshot) -> str:
        s = snap.sample
        n = snap.world_config.robots
        return (f"**In goal** {100 * s.fraction_in_goal:.1f} % &nbsp; "
                f"**stray distance** {s.mean_outside_distance:.2f} m  \n"
                f"**Charged robots** {s.charged_robots} / {n} &nbsp; **escaped boxes** {s.boxes_escaped}")

    # ========================================================== inspector
    def _build_inspector(self) -> None:
        gui = self.gui
        with gui.add_folder("Inspector"):
            self.inspect_help = gui.add_markdown("Click a robot on the floor to follow it.")
            self.inspect_text = gui.add_markdown("")
            self.charge_bar = gui.add_progress_bar(0.0, color="green", visible=False)
            self.camera_follow = gui.add_checkbox("Camera follows", False,
                                                  hint="Zoom in on the followed robot and keep it centred")
            self.follow_random = gui.add_button("Follow a random robot", icon=viser.Icon.TARGET)
            self.stop_follow = gui.add_button("Stop following", icon=viser.Icon.X, disabled=True)

        @self.follow_random.on_click
        def _(event: viser.GuiEvent) -> None:
            n = len(self.runner.latest.robot_positions)
            if n:
                i = int(np.random.default_rng().integers(0, n))
                self.runner.select(i)
                self.inspect_help.content = f"Following robot **{i}** (click another, or stop)."
                self.stop_follow.disabled = False

        @self.camera_follow.on_update
        def _(event: viser.GuiEvent) -> None:
            if not self.camera_follow.value:
                self._frame_arena()

        @self.stop_follow.on_click
        def _(event: viser.GuiEvent) -> None:
            self.runner.select(None)
            self.inspect_help.content = "Click a robot on the floor to follow it."
            self.inspect_text.content = ""
            self.charge_bar.visible = False
            self.stop_follow.disabled = True
            if self.camera_follow.value:
                self.camera_follow.value = False
                self._frame_arena()

    def _frame_arena(self) -> None:
        from sandbox.app.scene import top_down_camera

        position, look_at, _ = top_down_camera(self.runner.latest.world_config)
        for client in self.app.server.get_clients().values():
            with client.atomic():
                client.camera.position = tuple(position)
                client.camera.look_at = tuple(look_at)

    def _follow_with_cameras(self, snap: Snapshot) -> None:
        x, y = (float(v) for v in snap.robot.position)
        height = 12.0
        for client in self.app.server.get_clients().values():
            with client.atomic():
                client.camera.position = (x, y - 1e-3 * height, height)
                client.camera.look_at = (x, y, 0.0)

    def _inspect_text(self, snap: Snapshot) -> str:
        r = snap.robot
        if r is None:
            return ""
        names = PHOTOCELLS[snap.world_config.photocells].names
        v, w = r.command
        av, aw = r.applied
        cap = snap.world_config.capacity
        state = "moving" if r.charge > 0 else "**out of charge: stopped**"
        cells = "".join(f"| {name} | {reading:.3f} |\n" for name, reading in zip(names, r.sensors))
        return ("| photocell | reading |\n|---|---|\n" + cells + "\n"
                f"**Command** v = {v:+.3f} m/s, w = {w:+.3f} rad/s  \n"
                f"**Doing** v = {av:+.3f}, w = {aw:+.3f} ({state})  \n"
                f"**Charge** {r.charge:.2f} / {cap:g} &nbsp; at ({r.position[0]:.1f}, {r.position[1]:.1f}) m")

    # ============================================================= record
    def _build_record(self) -> None:
        gui = self.gui
        self._finished_html: str | None = None
        with gui.add_folder("Record", expand_by_default=False):
            gui.add_markdown("Capture the run and download it as one HTML file that replays in any browser, "
                             f"no server needed (at most {MAX_RECORD_SECONDS:.0f} s).")
            self.record_button = gui.add_button("Start recording", icon=viser.Icon.PLAYER_RECORD)
            self.record_status = gui.add_markdown("")

        @self.record_button.on_click
        def _(event: viser.GuiEvent) -> None:
            if self.recorder is None and self._finished_html is None:
                self.start_recording()
                return
            html = self.stop_recording()
            event.client.send_file_download("phototaxis-recording.html", html.encode("utf-8"),
                                            save_immediately=True)

    def start_recording(self) -> None:
        with self._lock:
            self.recorder = self.app.server.get_scene_serializer()
            self._record_started = self._last_record_time = time.perf_counter()
        self.record_button.label = "Stop and download"
        self.record_button.icon = viser.Icon.PLAYER_STOP
        self.record_status.content = "Recording..."

    def stop_recording(self) -> str:
        """Finish the recording; returns it as standalone HTML."""
        with self._lock:
            recorder, self.recorder = self.recorder, None
            html, self._finished_html = self._finished_html, None
        if recorder is not None:
            html = recorder.as_html(dark_mode=True)
        self.record_button.label = "Start recording"
        self.record_button.icon = viser.Icon.PLAYER_RECORD
        self.record_status.content = ""
        return html or ""

    def on_frame_drawn(self) -> None:
        """Called after each frame is drawn: advance the recording clock."""
        with self._lock:
            if self.recorder is None:
                return
            now = time.perf_counter()
            self.recorder.insert_sleep(now - self._last_record_time)
            self._last_record_time = now
            if now - self._record_started <= MAX_RECORD_SECONDS:
                return
            recorder, self.recorder = self.recorder, None
        self._finished_html = recorder.as_html(dark_mode=True)
        self.record_status.content = f"Stopped at {MAX_RECORD_SECONDS:.0f} s: press the button to download."
        self.record_button.label = "Download recording"
        self.record_button.icon = viser.Icon.DOWNLOAD

    # ========================================================= parameters
    def _build_parameters(self, snap: Snapshot) -> None:
        gui = self.gui
        self.param_controls: dict[str, Any] = {}
        with gui.add_folder("Population and physics", expand_by_default=False):
            self.pending = gui.add_markdown("")
            groups: dict[str, list] = {}
            for p in params():
                if p.name not in NOT_IN_PARAMETER_FOLDERS:
                    # Every value a profile sets sits with the profile, so a change of profile shows.
                    groups.setdefault("model" if p.profiled else p.group, []).append(p)
            for group in ("model", "bodies", "robot", "lights", "controller", "arena", "run", "physics"):
                if group not in groups:
                    continue
                with gui.add_folder(GROUP_TITLES.get(group, group), expand_by_default=group == "bodies"):
                    if group == "model":
                        gui.add_markdown(MODEL_HELP)
                    for p in groups[group]:
                        self.param_controls[p.name] = self._param_control(p, getattr(snap.config, p.name))

    def _param_control(self, p: Any, value: Any) -> Any:
        gui = self.gui
        unit = f" ({p.unit})" if p.unit and p.unit != "steps" else ""
        label = p.name.replace("_", " ") + unit
        hint = p.help + ("" if p.rebuild else " (applies at once)") + (" (applies on reset)" if p.rebuild else "")
        if p.choices:
            handle = gui.add_dropdown(label, tuple(p.choices), initial_value=value, hint=hint)
        elif p.type is int:
            handle = gui.add_number(label, int(value), min=int(p.low) if p.low is not None else None,
                                    max=int(p.high) if p.high is not None else None, step=1, hint=hint)
        else:
            handle = gui.add_number(label, float(value), min=p.low, max=p.high, step=_step_for(float(value)),
                                    hint=hint)

        @handle.on_update
        def _(event: viser.GuiEvent) -> None:
            self._param_changed(p.name, handle, event.client)

        return handle

    def _param_changed(self, name: str, handle: Any, client: Any) -> None:
        value = handle.value

        def done(result: tuple[list[str], Config]) -> None:
            deferred, config = result
            self._settings = config
            if name == "profile":
                self._show_profile_values(config)
            if deferred:
                self._pending.update(deferred)
                self.pending.content = ("**Applies on reset:** " + ", ".join(sorted(self._pending)) +
                                        " (press *Reset* in Run)")
                notify(client, "Applies on reset", f"{name} = {value} takes effect when you press Reset.", "yellow")

        def failed(exc: BaseException) -> None:
            notify_error(client, f"{name} not changed", str(exc))
            # Put the control back to the value in force.
            current = getattr(self._settings, name)
            threading.Thread(target=lambda: setattr(handle, "value", current), daemon=True).start()

        self.runner.post(functools.partial(update_config_and_report, **{name: value}), on_done=done, on_error=failed)

    def _show_profile_values(self, config: Config) -> None:
        """After a change of profile, show the values it set (they apply on reset)."""

        def show() -> None:
            for p in params():
                handle = self.param_controls.get(p.name)
                if p.profiled and handle is not None and handle.value != getattr(config, p.name):
                    handle.value = getattr(config, p.name)
                    self._pending.add(p.name)

        threading.Thread(target=show, daemon=True).start()

    # ============================================================== learn
    def _build_learn(self) -> None:
        gui = self.gui
        with gui.add_folder("Learn", expand_by_default=False):
            gui.add_markdown(learn.INTRO)
            gui.add_image(learn.phototaxis_picture(), format="png")
            gui.add_markdown(learn.CYCLE)
            gui.add_image(learn.cycle_picture(), format="png")
            gui.add_markdown(learn.STRATEGIES)
            gui.add_image(learn.strategies_picture(), format="png")
            gui.add_markdown(learn.INSPECT)

    # ============================================================ refresh
    def update(self, snap: Snapshot, force: bool = False) -> None:
        """Refresh the read-outs (throttled to PANEL_HZ)."""
        now = time.perf_counter()
        if not force and now - self._last_refresh < 1.0 / PANEL_HZ:
            return
        self._last_refresh = now
        self.status.content = self._status_text(snap)
        self.metrics_text.content = self._metrics_text(snap)
        if self.play.label != ("Pause" if snap.playing else "Play"):
            self._sync_play_button()
        shown = snap.shape_name if snap.shape_name in self.shape.options else CUSTOM_SHAPE
        if self.shape.value != shown and now - self._shape_picked_at > 2.0:  # not while a pick is on its way
            self.shape.value = shown
        series = self.runner.series()[-3000:]
        if len(series) >= 2:
            steps = np.array([s.step for s in series], float)
            self.chart_goal.data = (steps, np.array([s.fraction_in_goal for s in series]))
            self.chart_dist.data = (steps, np.array([s.mean_outside_distance for s in series]))
            self.chart_charged.data = (steps, np.array([s.charged_robots for s in series], float))
        if snap.robot is not None:
            self.inspect_text.content = self._inspect_text(snap)
            cap = snap.world_config.capacity
            self.charge_bar.value = float(100.0 * snap.robot.charge / cap) if cap > 0 else 0.0
            self.charge_bar.visible = True
            if self.camera_follow.value:
                self._follow_with_cameras(snap)
        if self.recorder is not None:
            self.record_status.content = f"Recording: {now - self._record_started:.0f} s"


def _step_for(value: float) -> float:
    if value == 0:
        return 0.01
    magnitude = 10 ** np.floor(np.log10(abs(value)))
    return float(magnitude / 100)
