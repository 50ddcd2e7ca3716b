"""Where the controller is in its cycle: the state its state machine
(:class:`sandbox.model.controller.Cycle`) changes, kept apart so that a copy
of it can be run ahead (chase counts its next cycle so)."""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

from sandbox.model.config import STRATEGY_NAMES, Config
from sandbox.model.goal import Goal
from sandbox.model.outlines import Sizing, sizing_for
from sandbox.model.phases import CONTRACTING

_NOTHING_PENDING: Mapping[str, float] = MappingProxyType({})


@dataclass
class Schedule:
    """Where the controller is in its cycle: with the configuration and the goal,
    everything its next sizes depend on. ``dataclasses.replace`` copies it: the
    sizing and the mappings are replaced when they change, never changed in
    place, so a copy shares nothing that moves."""

    sizing: Sizing  # the outline family for the strategies applied now
    strategies: Mapping[str, float]  # as applied now
    pending: Mapping[str, float]  # set live, applied at the next update
    scale: float  # the outline's size
    phase: str = CONTRACTING
    circle_radius: float | None = None  # the circle lit in the polygon's place (switch_mode 'inradius')
    cycle: int = 0  # completed contract -> hold -> dilate cycles
    updates: int = 0
    until_update: int = 0  # world steps to the next update
    hold_left: int = 0  # world steps the hold has left

    @classmethod
    def start(cls, config: Config, goal: Goal) -> Schedule:
        """A new cycle's: contracting from the largest size, the strategies as configured."""
        strategies = {name: getattr(config, name) for name in STRATEGY_NAMES}
        sizing = sizing_for(config, goal, strategies["flare"], strategies["chase"])
        return cls(sizing, MappingProxyType(strategies), _NOTHING_PENDING, sizing.largest,
                   until_update=config.update_every)

    # -- live changes: the mappings and the sizing are replaced, never changed in place --
    def reconfigure(self, config: Config, goal: Goal) -> None:
        """New controller values (rate, band, sizes...): the phase kept, the scale within the new limits."""
        self.resize(config, goal)
        self.until_update = min(self.until_update, config.update_every)
        if config.switch_mode != "inradius":
            self.circle_radius = None

    def set_pending(self, values: Mapping[str, float]) -> None:
        """Strategies to apply at the next update."""
        unknown = set(values) - set(self.strategies)
        if unknown:
            raise ValueError(f"unknown strategies: {sorted(unknown)}")
        self.pending = MappingProxyType({**self.pending, **values})

    def take_pending(self, config: Config, goal: Goal) -> None:
        """Apply the pending strategies (at an update)."""
        if not self.pending:
            return
        old = self.strategies
        self.strategies, self.pending = MappingProxyType({**self.strategies, **self.pending}), _NOTHING_PENDING
        # The sizing depends on flare, and on whether chase is on (an offset goal's notches are the open loop's).
        if self.strategies["flare"] != old["flare"] or (self.strategies["chase"] > 0) != (old["chase"] > 0):
            self.resize(config, goal)
        if self.strategies["switch"] <= 0:
            self.circle_radius = None

    def resize(self, config: Config, goal: Goal) -> None:
        """The outline family for the configuration and strategies now, the scale kept within it."""
        self.sizing = sizing_for(config, goal, self.strategies["flare"], self.strategies["chase"])
        self.scale = min(max(self.scale, self.sizing.smallest), self.sizing.largest)

    # -- sizes ------------------------------------------------------------
    @property
    def min_radius(self) -> float:
        """The smallest outline's inradius (its radius for a circle)."""
        return self.sizing.radius(self.sizing.smallest)

    @property
    def inradius(self) -> float:
        """The lit outline's inradius (its radius for a circle)."""
        return self.circle_radius if self.circle_radius is not None else self.sizing.radius(self.scale)

    @property
    def max_radius(self) -> float:
        """The inradius (radius for a circle) at which the lit outline turns from dilating."""
        if self.circle_radius is not None:
            return self.sizing.circle_largest
        return self.sizing.radius(self.sizing.turn)

    @property
    def progress(self) -> float:
        """How far the scale is from smallest (0) to largest (1)."""
        span = self.sizing.largest - self.sizing.smallest
        return 0.0 if span <= 0 else (self.scale - self.sizing.smallest) / span


class InSchedule:
    """An attribute of a cycle that its :class:`Schedule` keeps (read-only if the
    schedule's is)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, cycle, owner: type | None = None):
        return self if cycle is None else getattr(cycle.state, self.name)

    def __set__(self, cycle, value) -> None:
        setattr(cycle.state, self.name, value)
