"""Which settings a crashed simulation process is started again from, and how to say so (issue 54).
Written on the receiving thread of a child runner, read anywhere.

A world that kills its process (out of memory, say) while it is built or run from new settings kills
every process started again from them: the app used to restart "from the last settings" every 15-20 s
for as long as it ran, the teacher's page starved and could not set the values back. So the settings
that *stand* are those of the last world that ran: one that took :data:`PROVEN_STEPS` steps, or
stepped for :data:`PROVEN_SECONDS` (the settings the app started with stand until then). After a crash:

- with settings other than those that stand (a world being built from new values, a new goal, or a
  world running with them), the next process starts from the settings that stand, and the page is
  told which values failed;
- with the settings that stand, it starts from them again (and from the running world's seed); a second
  such crash before a world runs takes the settings that ran before those, when there are any.

:attr:`Standing.crashes` counts the crashes since a world last ran, however far apart: the process
runner gives up at five (it also gives up at five within a minute, worlds that ran or not).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from sandbox.model.config import Config

#: A world that took this many steps ran (a minute of the world's time at the default step of 1/30 s;
#: 1.3 s at the default speed) ...
PROVEN_STEPS = 1000
#: ... or that stepped for this long (s): a slow world (many bodies) runs too.
PROVEN_SECONDS = 10.0
#: How many sets of settings that ran are kept to go back to.
KEPT = 4
#: Settings that are not the world's: a seed does not make settings new; the goal is compared as given.
NOT_COMPARED = ("seed", "shape")
#: How many changed values a message names (then "and N more").
NAMED_AT_MOST = 4


@dataclass(frozen=True)
class Settings:
    """What a simulation process builds its world from: the configuration, the goal as
    :class:`~sandbox.app.world.child.ProcessRunner` keeps it ("from-config", None for the circle, or
    vertices as drawn) and the seed."""

    config: Config
    shape: Any
    seed: int | None

    def changed_from(self, other: "Settings") -> list[str]:
        """The names of the configuration's values that differ from ``other``'s (seed and goal aside)."""
        return changed(self.config, other.config)

    def same_goal(self, other: "Settings") -> bool:
        a, b = self.shape, other.shape
        if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
            return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
                    and bool(np.array_equal(a, b)))
        return a == b and self.config.shape == other.config.shape

    def same_world(self, other: "Settings") -> bool:
        return self.same_goal(other) and not self.changed_from(other)


def changed(config: Config, other: Config) -> list[str]:
    """The names of the values that differ between two configurations, in declaration order (the seed and
    the goal's name aside)."""
    return [f.name for f in dataclasses.fields(Config)
            if f.name not in NOT_COMPARED and getattr(config, f.name) != getattr(other, f.name)]


def values(config: Config, names: list[str]) -> str:
    """``light pitch 0.05, field samples 64``: the named values of ``config``, at most NAMED_AT_MOST."""
    shown = [f"{name.replace('_', ' ')} {_value(getattr(config, name))}" for name in names[:NAMED_AT_MOST]]
    if len(names) > NAMED_AT_MOST:
        shown.append(f"{len(names) - NAMED_AT_MOST} more")
    return ", ".join(shown)


def _value(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def gone_back(cause: str, failed: Settings, standing: Settings) -> str:
    """What the page is told when a crash with ``failed`` sends the simulation back to ``standing``:
    ``the simulation process stopped (...) with light pitch 0.05, field samples 64; back to the last
    settings that ran (light pitch 1, field samples 4)``. Numbers and names of the declared values only:
    no text a user gave (a goal is "another goal")."""
    names = failed.changed_from(standing)
    what = [values(failed.config, names)] if names else []
    if not failed.same_goal(standing):
        what.append("another goal")
    said = f"{cause} with {' and '.join(what)}" if what else cause
    back = f" ({values(standing.config, names)})" if names else ""
    return f"{said}; back to the last settings that ran{back}"


class Restart(NamedTuple):
    """The settings a new process starts from, and whether they are others than those that failed."""

    settings: Settings
    went_back: bool


class Standing:
    """The settings that ran (newest last) and the crashes since a world last ran. Changed on the
    process runner's receiving thread only; read anywhere."""

    def __init__(self, first: Settings):
        self._ran: list[Settings] = [first]
        #: Crashes since a world last ran (the app gives up at five, however far apart they are).
        self.crashes = 0
        self._crashes_standing = 0  # of these, crashes with the settings that stand

    @property
    def settings(self) -> Settings:
        """The settings that stand: the last that ran."""
        return self._ran[-1]

    def ran(self, settings: Settings) -> None:
        """A world from ``settings`` ran: they stand, and the count of crashes starts again."""
        self._ran = [s for s in self._ran if not s.same_world(settings)][-(KEPT - 1):] + [settings]
        self.crashes = self._crashes_standing = 0

    def crashed(self, failed: Settings) -> Restart:
        """A process building or running ``failed`` died: what the next one starts from."""
        self.crashes += 1
        if not failed.same_world(self.settings):
            return Restart(self.settings, True)
        self._crashes_standing += 1
        if self._crashes_standing >= 2 and len(self._ran) > 1:  # they failed twice: those before them
            self._ran.pop()
            self._crashes_standing = 0
            return Restart(self.settings, True)
        return Restart(failed, False)
