"""The Metrics folder: both success metrics and the charged robots, live and
as charts over the run, and the series as a CSV download. Runs on the app's event thread."""

from __future__ import annotations

import io
import time
from typing import Any, Callable

import numpy as np
import viser
import viser.uplot

from sandbox.app.view import palette as pal
from sandbox.app.world.lockstep import side_name
from sandbox.app.panel.plain import plain
from sandbox.app.world.snapshot import Snapshot
from sandbox.model.metrics import SampleWriter

#: A chart is about 300 px wide: more points than this are not seen, only sent.
CHART_POINTS = 300
#: Charts are sent to every viewer at most this often (s); the text above them is live.
CHART_PERIOD = 1.0


#: Changes made from the page show as white dots along the top of the first chart.
MARKS = {"label": "change", "stroke": "#ffffff", "width": 0, "points": {"show": True, "size": 9, "fill": "#ffffff"}}
#: Each chart's colour for compare mode's second world (the right one).
COMPARED_COLOUR = "#ffd23f"

#: The charts: (handle attribute, the sample's field, the series' label, its colour).
CHARTS = (("chart_goal", "fraction_in_goal", "in goal", "#ff5ca8"),
          ("chart_dist", "mean_outside_distance", "stray distance", "#40c8ff"),
          ("chart_charged", "charged_robots", "with charge", "#2ecc40"))
#: The *charts* dropdown: its choices and the charts each shows. Hidden charts are neither drawn nor
#: sent: a new page draws the whole panel in one task before it shows anything, and the three charts
#: cost a first visit about 0.5 s of it.
CHART_CHOICES = {"boxes in goal": ("chart_goal",), "stray distance": ("chart_dist",),
                 "robots with charge": ("chart_charged",), "all three": tuple(attr for attr, *_ in CHARTS),
                 "none": ()}
CHARTS_SHOWN_FIRST = "boxes in goal"


def curve_at(steps: np.ndarray, at: np.ndarray, values: np.ndarray) -> np.ndarray:
    """One world's curve (``values`` sampled at steps ``at``, in step order) read at ``steps`` (the other
    world's), drawn straight between two samples; NaN outside them (no curve where that world has not
    been). Each world samples at the end of its own frames, and two worlds in lockstep may end them on
    different steps (up to compare.LEAD_FRAMES frames apart), so the two series rarely share a step."""
    if len(at) == 0:
        return np.full(len(steps), np.nan, np.float32)
    return np.interp(steps, at, values, left=np.nan, right=np.nan).astype(np.float32)


class MetricsFolder:
    def __init__(self, gui: Any, runner: Any, compared: Callable[[], Any] = lambda: None):
        """``compared()``: compare mode's second runner, or None; its curves join the charts."""
        self.gui, self.runner, self._compared = gui, runner, compared
        #: (step, what) of every change made from the page: shape, strategy, case, reset.
        self.marks: list[tuple[int, str]] = []
        self._charted: tuple | None = None  # what the charts last showed
        self.shown: tuple[str, ...] = CHART_CHOICES[CHARTS_SHOWN_FIRST]  # the charts on the page
        self._charted_at = 0.0
        #: The series (curves and their names) each chart shows: compare mode adds the second world's.
        self._series_shown = {attr: self._series(label, colour, None, marks=attr == "chart_goal")
                              for attr, _, label, colour in CHARTS}

    def mark(self, what: str, step: int | None = None) -> None:
        """Remember a change, to show on the charts where it happened (``step`` None: now)."""
        if what == "reset":
            self.marks = []
            self.marks.append((0, what))
        else:
            self.marks.append((self.runner.latest.step if step is None else step, what))

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Metrics"):
            self.text = gui.add_markdown(self._text(snap))
            self.choice = gui.add_dropdown("charts", tuple(CHART_CHOICES), initial_value=CHARTS_SHOWN_FIRST,
                                           hint="Which charts over the run to show")
            x = np.array([0.0, 0.0])
            # x is the world step (not a date: "time": False below).
            # The legend under each chart is uPlot's live one: it shows the values under the pointer.
            # The y axis asks for a tick every 22 px, so that even a short chart has three or more.
            common = dict(height=150, padding=(8, 12, 0, 0), legend={"show": True, "live": True},
                          axes=({"stroke": "#c8cbd2"}, {"stroke": "#c8cbd2", "space": 22}))
            self.chart_goal = gui.add_uplot(
                (x, x, np.full(2, np.nan)),
                self._series_shown["chart_goal"],
                title="Boxes in goal (fraction) vs step; dots: changes", scales={"x": {"time": False},
                                                                                  "y": {"range": [0, 1]}},
                **common)
            self.chart_dist = gui.add_uplot(
                (x, x), self._series_shown["chart_dist"],
                title="Mean distance of stray boxes (m)", scales={"x": {"time": False}}, **common)
            self.chart_charged = gui.add_uplot(
                (x, x), self._series_shown["chart_charged"],
                title="Robots with any charge (green or amber)", scales={"x": {"time": False}}, **common)
            self._show_only(self.shown)
            self.download_csv = gui.add_button("Download CSV", icon=viser.Icon.FILE_SPREADSHEET,
                                               hint="The metrics time series of this run")

        @self.download_csv.on_click
        def _(event: viser.GuiEvent) -> None:
            event.client.send_file_download("phototaxis-metrics.csv", self.csv().encode("utf-8"),
                                            save_immediately=True)

        @self.choice.on_update
        def _(event: viser.GuiEvent) -> None:
            self.show_charts(self.choice.value)

    def show_charts(self, choice: str) -> None:
        """Show the charts ``choice`` names (on every page: the panel is shared), each with the whole run
        at once, paused or not (a hidden chart is not sent its data)."""
        if choice not in CHART_CHOICES:
            raise ValueError(f"no chart choice {choice!r}")
        self._show_only(CHART_CHOICES[choice])
        self._charted_at = 0.0  # now, not a period later (what is shown is part of what was charted)
        self.update(self.runner.latest)

    def _show_only(self, shown: tuple[str, ...]) -> None:
        self.shown = shown
        for attr, *_ in CHARTS:
            getattr(self, attr).visible = attr in shown

    def update(self, snap: Snapshot) -> None:
        partner = self._compared()
        self.text.content = self._text(snap) + ("" if partner is None else self._compared_text(partner.latest))
        series = self.runner.series()
        # Every chart update goes to every viewer: send one only when there is something new to
        # draw, at most once per CHART_PERIOD, and as at most CHART_POINTS points of the whole run.
        # (Sending all samples at each panel refresh cost 31 KB/s per viewer after 20 s, growing
        # to about 900 KB/s once the series held its old cap of 3,000 samples.)
        other = partner.series() if partner is not None else None
        names = None if partner is None else (side_name(snap), side_name(partner.latest))
        key = (len(series), series[-1].step if series else None, tuple(self.marks),
               None if other is None else (len(other), names), self.shown)
        now = time.monotonic()
        if not self.shown or len(series) < 2 or key == self._charted or now - self._charted_at < CHART_PERIOD:
            return
        self._charted, self._charted_at = key, now
        shown = [series[i] for i in chart_indices(len(series), CHART_POINTS)]
        steps = np.array([s.step for s in shown], np.float32)
        other_steps = None if other is None else np.array([s.step for s in other], np.float64)
        # (The app sends a frame's scene and panel changes in one batch: series and data arrive together.)
        for attr, field, label, colour in CHARTS:
            if attr not in self.shown:
                continue
            chart = getattr(self, attr)
            data = [steps, np.array([getattr(s, field) for s in shown], np.float32)]
            if other is not None:  # the second world's curve, read at this world's steps
                data.append(curve_at(steps, other_steps, np.array([getattr(s, field) for s in other], np.float64)))
            if attr == "chart_goal":
                data.append(self.mark_series(steps).astype(np.float32))
            series_shown = self._series(label, colour, names, marks=attr == "chart_goal")
            if self._series_shown[attr] != series_shown:
                chart.series = self._series_shown[attr] = series_shown
            chart.data = tuple(data)

    @staticmethod
    def _series(label: str, colour: str, names: tuple[str, str] | None, marks: bool) -> tuple:
        """A chart's series: the step, this world's curve, in compare mode the second world's
        (named after each world), and the change dots."""
        line = {"stroke": colour, "width": 2}
        if names is None:
            curves = ({"label": label, **line},)
        else:
            curves = ({"label": f"{label}: {names[0]} (left)", **line},
                      {"label": f"{names[1]} (right)", "stroke": COMPARED_COLOUR, "width": 2})
        return ({"label": "step"}, *curves, *((MARKS,) if marks else ()))

    def mark_series(self, steps: np.ndarray) -> np.ndarray:
        """1.0 at the first sample at or after each change, NaN elsewhere."""
        out = np.full(len(steps), np.nan)
        for step, _ in self.marks:
            i = int(np.searchsorted(steps, step))
            if i < len(steps):
                out[i] = 1.0
        return out

    def csv(self) -> str:  # every sample, not just the charted ones
        """The run's samples as CSV, with the time in seconds as the last column; in compare mode
        both worlds', each row led by its world (``left: star``, ``right: star-switch``)."""
        out = io.StringIO()
        dt = self.runner.latest.world_config.dt
        partner = self._compared()
        if partner is None:
            writer = SampleWriter(out, trailing=("time",))
            for s in self.runner.series():
                writer.write(s, time=round(s.step * dt, 4))
            return out.getvalue()
        writer = SampleWriter(out, leading=("world",), trailing=("time",))
        for side, runner in (("left", self.runner), ("right", partner)):
            world = f"{side}: {side_name(runner.latest)}"
            for s in runner.series():
                writer.write(s, world=world, time=round(s.step * dt, 4))
        return out.getvalue()

    @staticmethod
    def _compared_text(other: Snapshot) -> str:
        """Compare mode: the second world's metrics under the first's (the charts' yellow curves)."""
        s = other.sample
        return (f"  \n**Right** ({plain(side_name(other))}): **in goal** {100 * s.fraction_in_goal:.1f} % &nbsp; "
                f"**stray distance** {s.mean_outside_distance:.2f} m")

    @staticmethod
    def _text(snap: Snapshot) -> str:
        s = snap.sample
        charged, low, empty = pal.charge_counts(snap.robot_charges, snap.world_config.capacity)
        return (f"**In goal** {100 * s.fraction_in_goal:.1f} % &nbsp; "
                f"**stray distance** {s.mean_outside_distance:.2f} m  \n"
                f"**Robots** {charged} charged (green, more than half full), {low} low (amber), "
                f"{empty} empty (red) &nbsp; **escaped boxes** {s.boxes_escaped}")


def chart_indices(n: int, points: int) -> np.ndarray:
    """Indices of at most ``points`` samples spread evenly over ``n``, first and last included."""
    if n <= points:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, points)).astype(int))
