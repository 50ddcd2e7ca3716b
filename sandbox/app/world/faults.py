"""Faults the tests put into a simulation process: a world that is slow to build, or one whose building
kills its process (as running out of memory does), so that what the app does then can be tested
without exhausting the machine's memory or waiting on a real slow build.
Read in the child process as a world is built.

Each is an environment variable of the app's process, read by :class:`~sandbox.app.world.child.ProcessRunner`
each time it starts a simulation process and handed to it with its settings; the simulation process
then wraps the building of every world (:func:`install`). Nothing a page sends reaches them, and with
neither set (outside the tests) nothing changes.

- ``PHOTOTAXIS_TEST_SLOW_BUILD=SECONDS``: every world takes this long more to build (a sleep first);
- ``PHOTOTAXIS_TEST_CRASH_BUILD=NAME=VALUE``: building a world whose setting NAME has this value kills
  its process (SIGKILL, as the kernel's out-of-memory killer does), e.g. ``light_pitch=0.5``.
"""

from __future__ import annotations

import os
import signal
import time
from dataclasses import dataclass
from typing import Any, Mapping

SLOW_BUILD = "PHOTOTAXIS_TEST_SLOW_BUILD"
CRASH_BUILD = "PHOTOTAXIS_TEST_CRASH_BUILD"


@dataclass(frozen=True)
class Faults:
    """What a simulation process is to do wrong: build slowly (seconds), die building a world whose
    setting ``crash_when[0]`` reads ``crash_when[1]``."""

    slow_build: float = 0.0
    crash_when: tuple[str, str] | None = None

    def crashes(self, config: Any) -> bool:
        if self.crash_when is None:
            return False
        name, value = self.crash_when
        return str(getattr(config, name, None)) == value


def from_environment(environ: Mapping[str, str] = os.environ) -> Faults | None:
    """The faults the environment asks for, or None (the usual case)."""
    slow, crash = environ.get(SLOW_BUILD), environ.get(CRASH_BUILD)
    if not slow and not crash:
        return None
    crash_when = tuple(part.strip() for part in crash.split("=", 1)) if crash and "=" in crash else None
    return Faults(slow_build=float(slow or 0.0), crash_when=crash_when)


def install(faults: Faults | None) -> None:
    """In a simulation process: every world is built through the faults (nothing with None)."""
    if faults is None:
        return
    from sandbox.model import simulation

    build = simulation.World

    def world(config: Any, *args: Any, **kwargs: Any) -> Any:
        if faults.slow_build > 0:
            time.sleep(faults.slow_build)
        if faults.crashes(config):
            os.kill(os.getpid(), signal.SIGKILL)
        return build(config, *args, **kwargs)

    simulation.World = world
