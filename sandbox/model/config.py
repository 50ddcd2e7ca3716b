"""Every parameter of the model, declared once.

Each field of :class:`Config` carries its default, unit, allowed range, help
text and group in its metadata. The CLI flags, the config-file loader, the
browser panel and the result files are all generated from these declarations
(see :func:`params`), so a new parameter needs to be added here only.
Defaults follow ``SPEC.md``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from sandbox.model import budget
from sandbox.model.config_error import ConfigError  # (raised here and by the budget; imported from here)


#: The two profiles (SPEC §9). The default is the authors' program: it is
#: what produced the paper's tables.
AUTHORS_CODE, PAPER_TEXT = "authors-code", "paper-text"
PROFILES_NAMES = (AUTHORS_CODE, PAPER_TEXT)


def _param(
    default: Any,
    help: str,
    *,
    unit: str = "",
    low: float | None = None,
    high: float | None = None,
    group: str,
    choices: tuple[str, ...] | None = None,
    rebuild: bool = True,
    paper: Any = None,
) -> Any:
    """Declare one parameter. ``rebuild`` says whether a change needs a reset.

    ``paper``, when given, is the parameter's value in the ``paper-text``
    profile and ``default`` its value in ``authors-code``: the parameter is
    then *profiled*, and a :class:`Config` that is not given it explicitly
    takes the value of its profile.
    """
    meta = dict(help=help, unit=unit, low=low, high=high, group=group, choices=choices, rebuild=rebuild,
                profiled=paper is not None, profile_values={AUTHORS_CODE: default, PAPER_TEXT: paper})
    # A profiled field defaults to None ("whatever the profile says"), resolved in __post_init__.
    return field(default=None if paper is not None else default, metadata=meta)


@dataclass(frozen=True)
class Strategy:
    """One of the controller's strategies, declared once: the config field,
    the command-line flag (bare = ``on_value``), the panel's checkbox and
    slider, the run summary and the controller all come from here."""

    name: str
    label: str
    on_value: float  # the amount when switched on without one
    high: float  # the largest amount allowed (0 is off)
    step: float  # the panel slider's step, and its smallest amount
    help: str
    #: The panel's tooltip: at most two short lines in plain words (help is the full reference).
    tip: str = ""
    #: Why it does nothing, whatever its amount, with the offset outline, in a clause ('' when it does
    #: something there): sandbox.model.notes says so, and the page greys it out.
    offset_inert: str = ""


STRATEGIES = (
    Strategy("flare", "Flare", 1.75, 10.0, 0.05,
             "flare amount f (0 = off; 1.75 when switched on): corners pushed out by max(1, 90 f / angle), "
             "see flare_mode",
             tip="Pushes the outline's corners out, sharp ones most, so robots reach into corners. "
                 "Flare amount: how far (1.75 when switched on).",
             offset_inert="its band already rounds every corner at the same distance as the edges"),
    Strategy("switch", "Switch to circle", 0.25, 1.0, 0.05,
             "switch to a circle (0 = off; 0.25 when on): see switch_mode for what the amount means",
             tip="Grows back as a circle, so robots spread evenly instead of bunching at far points. "
                 "Switch to circle amount: how soon (0.25 when switched on).",
             offset_inert="far from the goal its band is nearly a circle already"),
    Strategy("no_corners", "No corners", 0.5, 0.95, 0.05,
             "fraction of band lights nearest convex corners that stay off (0 = off; 0.5 when on; at most "
             "0.95: at 1 the whole band would be dark)",
             tip="Leaves the lights nearest the corners dark, so robots do not pile up in sharp points. "
                 "No corners amount: the share left dark.",
             offset_inert="its band has no convex corners to darken"),
    Strategy("chase", "Chase stray boxes", 2.0, 10.0, 0.25,
             "closed loop (senses the boxes, as an overhead camera would): the outline is the goal grown by "
             "the same distance all round; it dilates only until it is this many metres beyond the farthest "
             "stray box; near the goal it presses in where boxes spill out and goes dark where the goal lacks "
             "boxes, and the smallest outline is held while boxes keep arriving; a run of fixed length ends in a "
             "hold, its dilations turning back in time and its last cycle timed to end just before its last "
             "step (0 = off, open loop; 2.0 when on)",
             tip="Closed loop: watches the boxes and turns back just past the farthest stray one. "
                 "Chase stray boxes amount: how far past it, in metres."),
)
STRATEGY_NAMES = tuple(s.name for s in STRATEGIES)
#: The value a strategy takes when it is switched on without an amount.
STRATEGY_DEFAULTS = {s.name: s.on_value for s in STRATEGIES}


def _strategy(name: str) -> Any:
    strategy = next(s for s in STRATEGIES if s.name == name)
    return _param(0.0, strategy.help, low=0.0, high=strategy.high, group="strategies", rebuild=False)


@dataclass(frozen=True)
class Config:
    """The full, typed configuration of one simulation run.

    ``profile`` names a bundle of values for the parameters where the
    paper's text and the authors' released program differ (SPEC §9); every
    one of them can still be set on its own, and an explicit value always
    wins over the profile's.
    """

    profile: str = _param(
        AUTHORS_CODE, "bundle of model values: 'authors-code' (the authors' released program, which produced "
        "the paper's tables) or 'paper-text' (the paper's written model); any value set explicitly wins",
        group="model", choices=PROFILES_NAMES)

    # --- arena (SPEC §2) -------------------------------------------------
    arena_size: float = _param(64.0, "side of the square arena", unit="m", low=2.0, high=2000.0, group="arena")
    construction_size: float = _param(
        16.0, "side of the central construction area whose wall stops boxes but not robots",
        unit="m", low=1.0, high=2000.0, group="arena")
    robot_spawn_size: float = _param(
        32.0, "side of the central square robots start in (outside the construction area)",
        unit="m", low=1.0, high=2000.0, group="arena")
    assembly_centre: str = _param(
        "light", "where the construction area, spawn square, goal and light outlines are centred: 'arena' "
        "(the arena's centre, between four lights) or 'light' (the light half a pitch up and right of it, "
        "as the authors' program does)", group="arena", choices=("light", "arena"), paper="arena")
    dt: float = _param(1 / 30, "physics time step (one world step)", unit="s", low=1e-4, high=1.0, group="arena")

    # --- bodies (SPEC §2) ------------------------------------------------
    robots: int = _param(200, "number of robots", low=0, high=100_000, group="bodies")
    robot_radius: float = _param(0.25, "robot radius", unit="m", low=0.01, high=10.0, group="bodies")
    robot_density: float = _param(10.0, "robot density", unit="kg/m^2", low=1e-3, high=1e4, group="bodies")
    robot_friction: float = _param(1.0, "robot friction coefficient", low=0.0, high=10.0, group="bodies")
    robot_elasticity: float = _param(0.0, "robot restitution", low=0.0, high=1.0, group="bodies")
    boxes: int = _param(500, "number of hexagonal boxes", low=0, high=100_000, group="bodies")
    box_size: float = _param(
        0.25, "hexagon size: apothem or circumradius, see box_size_is", unit="m", low=0.01, high=10.0, group="bodies")
    box_size_is: str = _param(
        "circumradius", "what box_size measures: 'apothem' (paper text) or 'circumradius' (authors' program)",
        group="bodies", choices=("apothem", "circumradius"), paper="apothem")
    box_start: str = _param(
        "scattered", "where the boxes start: 'scattered' (uniformly at random in the construction area, as in "
        "the paper) or 'packed' (a hexagonal tiling of the goal, filled from the inside out: the goal already "
        "built, to see what a light program keeps of it)", group="bodies", choices=("scattered", "packed"))
    box_density: float = _param(0.5, "box density", unit="kg/m^2", low=1e-3, high=1e4, group="bodies")
    box_friction: float = _param(1.0, "box friction coefficient", low=0.0, high=10.0, group="bodies")
    box_elasticity: float = _param(0.1, "box restitution", low=0.0, high=1.0, group="bodies")
    box_skin: float = _param(
        0.01, "rounding radius added around each box's hexagon for collisions (Box2D, the authors' engine, "
        "gives every polygon a 0.01 m skin, so boxes touch 0.02 m apart)", unit="m", low=0.0, high=1.0,
        group="bodies", paper=0.0)
    wall_friction: float = _param(
        0.4472, "friction coefficient between the walls and a body of friction 1 (Box2D's default wall "
        "friction 0.2 mixed with 1.0 as sqrt(0.2 x 1.0) in the authors' program; pymunk multiplies the two)",
        low=0.0, high=10.0, group="bodies", paper=1.0)
    box_damping: float = _param(
        10.0, "linear and angular damping of boxes (the box slides only while pushed)",
        unit="1/s", low=0.0, high=1000.0, group="bodies")
    box_damping_model: str = _param(
        "box2d", "how box_damping c slows a box each step: 'exponential', v *= exp(-c dt) (paper text), or "
        "'box2d', v *= 1 / (1 + c dt) (Box2D, the authors' program)", group="bodies",
        choices=("box2d", "exponential"), paper="exponential")

    # --- light grid (SPEC §3) --------------------------------------------
    light_pitch: float = _param(1.0, "spacing of the overhead lights", unit="m", low=0.05, high=100.0, group="lights")
    light_height: float = _param(
        2.0, "height of the lights above the floor (paper text 1, authors' program 2)",
        unit="m", low=0.01, high=100.0, group="lights", paper=1.0)
    light_falloff: float = _param(
        2.0, "falloff exponent k in B = I / d^k, d the 3-D distance (paper text 1, authors' program 2)",
        low=0.0, high=6.0, group="lights", paper=1.0)
    light_angle: str = _param(
        "squared-offsets", "angle factor of a light: 'elevation', sin(theta) = h / d (paper text), or "
        "'squared-offsets', sin(atan2(h, hypot(dx^2, dy^2))) (the authors' program: the offsets enter "
        "squared, so the field stays local)", group="lights", choices=("squared-offsets", "elevation"),
        paper="elevation")
    light_range: float = _param(
        12.8, "lights further than this in x or y do not reach a point", unit="m", low=0.1, high=2000.0, group="lights")
    light_window: str = _param(
        "cells", "which lights reach a point: 'range', those within light_range in x and y (paper text), or "
        "'cells', light cells floor(x)-W .. floor(x)+W-1 with W = floor(light_range / pitch), never the last "
        "row or column (the authors' program)", group="lights", choices=("cells", "range"), paper="range")
    light_intensity: float = _param(1.0, "intensity of a light that is on", low=0.0, high=1000.0, group="lights")
    field_samples: int = _param(
        6, "luminosity-field samples per light pitch, at least (more is finer and slower to rebuild)",
        low=1, high=64, group="lights")

    # --- robots (SPEC §4) ------------------------------------------------
    sensor_offset: float = _param(
        0.1, "distance of each photocell from the robot's centre along each body axis",
        unit="m", low=0.0, high=10.0, group="robot")
    photocells: str = _param(
        "corners", "where the four photocells sit: 'axes', front/back/left/right (paper text), or 'corners', "
        "(+-offset, +-offset) in the body frame (the authors' program)", group="robot",
        choices=("corners", "axes"), paper="axes")
    steering: str = _param(
        "front", "which photocells steer, w = k_turn (left - right): 'sides', every cell on each side (paper "
        "text), or 'front', only the front pair (the authors' program); the same for 'axes' photocells",
        group="robot", choices=("front", "sides"), paper="sides")
    k_drive: float = _param(5.0, "forward speed gain: v = k_drive (front - back)", low=0.0, high=1e4, group="robot", rebuild=False)
    k_turn: float = _param(20.0, "turn rate gain: w = k_turn (left - right)", low=0.0, high=1e4, group="robot", rebuild=False)
    command_period: int = _param(
        50, "steps a robot holds its command before it reads its photocells again",
        unit="steps", low=1, high=100_000, group="robot")
    motor: str = _param(
        "set-once", "'continuous': the command is the body's velocity every step (paper text); 'set-once': at "
        "each refresh the velocity is set once along the heading, then collisions change it and it persists, "
        "robots undamped (the authors' program)", group="robot", choices=("set-once", "continuous"),
        paper="continuous")
    eta_in: float = _param(0.4, "charge gained per unit of luminosity per step", low=0.0, high=1e4, group="robot", rebuild=False)
    metabolic: float = _param(0.01, "charge spent per step just to live", low=0.0, high=1e4, group="robot", rebuild=False)
    eta_out: float = _param(0.1, "charge spent per unit of motion per step, see energy_turn_cost", low=0.0, high=1e4, group="robot", rebuild=False)
    energy_turn_cost: str = _param(
        "signed", "motion cost: 'absolute', eta_out (|v| + |w|) of the command (paper text), or 'signed', "
        "eta_out (speed + w) of the body's actual motion with w signed, so turning clockwise gains charge "
        "(the authors' program)", group="robot", choices=("signed", "absolute"), paper="absolute")
    capacity: float = _param(20.0, "largest charge a robot stores", low=0.0, high=1e6, group="robot", rebuild=False)
    start_charge: float = _param(0.0, "charge of every robot at reset", low=0.0, high=1e6, group="robot")

    # --- controller (SPEC §5) --------------------------------------------
    shape: str = _param(
        "circle", "goal shape: 'circle', a name in shapes/, or a polygon file", group="controller", rebuild=False)
    update_every: int = _param(100, "steps between controller updates", unit="steps", low=1, high=1_000_000, group="controller", rebuild=False)
    scale_rate: float = _param(
        0.975, "outline scale factor per update while contracting (see size_schedule for dilating)",
        low=0.5, high=0.9999, group="controller", rebuild=False)
    size_schedule: str = _param(
        "program", "'clamped': contract by scale_rate and dilate by its inverse, clamped to the smallest and "
        "largest size (paper text); 'program': contract until the first size below the smallest, which is lit, "
        "grow back to it, dilate by 2 - scale_rate until the first size above the largest, which is skipped "
        "(the authors' program)", group="controller", choices=("program", "clamped"), paper="clamped",
        rebuild=False)
    hold_steps: int = _param(
        100, "world steps the smallest outline stays lit (paper text: t = 25 steps; the authors' program: one "
        "controller update)", unit="steps", low=0, high=1_000_000, group="controller", rebuild=False, paper=25)
    min_size_rule: str = _param(
        "inradius", "smallest outline: 'equal-area', the goal's equal-area radius plus one robot diameter "
        "(paper text), or 'inradius', the drawn outline's inradius equals the goal's plus one robot diameter "
        "(the authors' program)", group="controller", choices=("inradius", "equal-area"), paper="equal-area",
        rebuild=False)
    band: float = _param(
        0.5, "a light is on when its centre is within this distance of the outline",
        unit="m", low=0.0, high=100.0, group="controller", rebuild=False)
    circle_max: float = _param(
        0.75, "largest circle radius, as a fraction of half the arena width", low=0.05, high=1.0, group="controller", rebuild=False)
    polygon_max_area: float = _param(
        0.5, "largest polygon outline, as a fraction of the arena's area (capped to stay inside)",
        low=0.01, high=1.0, group="controller", rebuild=False)
    polygon_max_rule: str = _param(
        "grow", "largest polygon: 'fit', the largest scale inside the arena (one pitch clear) up to "
        "polygon_max_area (paper text), or 'grow', the file's outline grown by 1.05 until it covers "
        "polygon_max_area or reaches the arena's edge, keeping that step (the authors' program)",
        group="controller", choices=("grow", "fit"), paper="fit", rebuild=False)
    flare: float = _strategy("flare")
    flare_mode: str = _param(
        "scaled-outline", "'on-goal': convex corners of the goal pushed out, sizes from the goal (paper text); "
        "'scaled-outline': every corner pushed out by 90 f / |angle between its edges|, and that outline, "
        "matched to the goal's area, is what is scaled and sized (the authors' program)",
        group="strategies", choices=("scaled-outline", "on-goal"), paper="on-goal", rebuild=False)
    switch: float = _strategy("switch")
    switch_mode: str = _param(
        "inradius", "'fraction': a circle from 'switch' of the way between smallest and largest, both ways "
        "(paper text); 'inradius': only while dilating, once the polygon's inradius passes switch x half the "
        "arena (8 m), light a circle of that radius, grow it to the circle's largest, contract it and restore "
        "the polygon below the same radius (the authors' program)", group="strategies",
        choices=("inradius", "fraction"), paper="fraction", rebuild=False)
    no_corners: float = _strategy("no_corners")
    chase: float = _strategy("chase")
    outline: str = _param(
        "auto", "the outline the band follows: 'scaled', the goal scaled about the assembly centre (the paper); "
        "'offset', the goal grown by a distance, contracted to one robot diameter (builds any simple polygon); "
        "'auto', scaled when the centre lies deep inside the goal (its distance to the edge at least a third "
        "of its distance to the farthest vertex) and the smallest scaled outline fits, else offset",
        group="strategies", choices=("auto", "scaled", "offset"), rebuild=False)
    notches: str = _param(
        "lit", "the offset outline on a goal with notches (gaps narrower than 3 m): 'lit', every light in a "
        "notch lit while the band contracts within 2 m of it, the band at 0.4 of its pace within 3.5 m of "
        "the goal, so the robots clear the notch before the band presses, and the band held 0.65 m or more from "
        "the goal, farther beside thin parts, tips and corners (issue 42); 'plain', the band alone. "
        "Open loop only: chase lights its own band",
        group="strategies", choices=("lit", "plain"), rebuild=False)
    gather: str = _param(
        "auto", "the offset outline on a goal with lit notches in line whose mouths face opposite sides (an H, a K, "
        "an N, an X, a W): 'auto', while the band dilates beyond 2.5 m of the goal only its lights beyond the "
        "sides no mouth faces stay lit, so the robots the notches let out come back to those sides (issue 42); "
        "'off', the whole band", group="strategies", choices=("auto", "off"), rebuild=False)
    no_corners_count: str = _param(
        "at-least", "how many lights no_corners c turns off of n lit: 'round', round(c n), equally near lights "
        "taken column by column (paper text), or 'at-least', the fewest k with k / n >= c, row by row (the "
        "authors' program)", group="strategies", choices=("at-least", "round"), paper="round", rebuild=False)

    # --- run -------------------------------------------------------------
    steps: int = _param(100_000, "world steps in a run", unit="steps", low=0, high=10**9, group="run", rebuild=False)
    seed: int = _param(0, "random seed: the same seed and configuration give the same run", low=0, high=2**63 - 1, group="run")
    metrics_every: int = _param(1000, "steps between metric samples", unit="steps", low=1, high=10**9, group="run", rebuild=False)

    # --- physics engine tuning (not part of the model) -------------------
    iterations: int = _param(10, "pymunk solver iterations per step", low=1, high=100, group="physics")
    threads: int = _param(1, "pymunk solver threads (1 or 2; 2 uses pymunk's threaded solver)", low=1, high=2, group="physics")
    collision_slop: float = _param(
        0.005, "allowed overlap between shapes (Box2D, the authors' engine, allows its linearSlop, 0.005 m)",
        unit="m", low=0.0, high=1.0, group="physics", paper=0.01)
    sleep_time: float = _param(
        0.5, "a group of touching bodies that has moved slower than idle_speed for this long sleeps until "
        "something awake touches it (0 = never; Box2D, the authors' engine, uses 0.5 s)", unit="s", low=0.0,
        high=100.0, group="physics", paper=0.0)
    idle_speed: float = _param(
        0.01, "speed below which a body counts as at rest, for sleep_time (Box2D: 0.01 m/s)",
        unit="m/s", low=0.0, high=10.0, group="physics")

    def __post_init__(self) -> None:
        check_value("profile", self.profile)
        for f in dataclasses.fields(self):
            if getattr(self, f.name) is None and f.metadata["profiled"]:
                # Not given: the profile's value (the dataclass is frozen, hence object.__setattr__).
                object.__setattr__(self, f.name, f.metadata["profile_values"][self.profile])
        for f in dataclasses.fields(self):
            check_value(f.name, getattr(self, f.name))
        if self.construction_size >= self.arena_size:
            raise ConfigError("construction_size must be smaller than arena_size")
        if self.robot_spawn_size > self.arena_size:
            raise ConfigError("robot_spawn_size must not exceed arena_size")
        cells = self.arena_size / self.light_pitch
        if abs(cells - round(cells)) > 1e-6:
            raise ConfigError(
                f"arena_size ({self.arena_size}) must be a whole number of light_pitch ({self.light_pitch})")
        if self.light_window == "cells" and math.floor(self.light_range / self.light_pitch + 1e-9) < 1:
            # The program's window reaches floor(light_range / pitch) cells each way: none, and no light
            # would reach the floor (building the field failed with a traceback).
            raise ConfigError(f"light_range ({self.light_range:g}) must be at least light_pitch ({self.light_pitch:g}) "
                              f"with light_window 'cells': a light reaches light_range / light_pitch cells each way")
        self._check_populations()
        self._check_budget()

    def _check_populations(self) -> None:
        """Refuse populations that cannot be placed: robots in the spawn square
        outside the construction area, boxes inside it (about a robot's square,
        or a box's hexagon with room to spare, each)."""
        if self.robot_spawn_size <= self.construction_size + 2 * self.robot_radius and self.robots:
            raise ConfigError(f"robots: the spawn square ({self.robot_spawn_size:g} m) leaves no room outside "
                              f"the construction area ({self.construction_size:g} m)")
        if self.robots > self.max_robots:
            raise ConfigError(f"robots: {self.robots:,} robots of radius {self.robot_radius:g} m do not fit in the "
                              f"{self.robot_spawn_size:g} m spawn square outside the {self.construction_size:g} m "
                              f"construction area; at most {self.max_robots:,} do")
        if self.boxes > self.max_boxes:
            raise ConfigError(f"boxes: {self.boxes:,} boxes of {self.box_size_is} {self.box_size:g} m do not fit in the "
                              f"{self.construction_size:g} m construction area; at most {self.max_boxes:,} do")

    def _check_budget(self) -> None:
        """Refuse settings whose world would need more memory than the budget (sandbox.model.budget):
        here, so that no configuration a command, a file or the page makes can bypass it."""
        if budget.budget_checked():
            budget.check_settings(self)

    # Derived quantities -------------------------------------------------
    @property
    def max_robots(self) -> int:
        """Robots that fit where they start: one robot-wide square each in the spawn square outside the
        construction area (and its border of one radius)."""
        free = self.robot_spawn_size**2 - (self.construction_size + 2 * self.robot_radius) ** 2
        return max(0, int(free / (2 * self.robot_radius) ** 2))

    @property
    def max_boxes(self) -> int:
        """Boxes that fit in the construction area, each with half again its own area (packing room)."""
        inner = max(0.0, self.construction_size - 2 * self.box_circumradius) ** 2
        return int(inner / (1.5 * self.box_area))
    @property
    def lights_per_side(self) -> int:
        return int(round(self.arena_size / self.light_pitch))

    @property
    def centre(self) -> float:
        """x (and y) of the assembly centre: construction area, spawn square,
        goal and light outlines are centred on (centre, centre)."""
        if self.assembly_centre == "arena":
            return self.arena_size / 2.0
        # The light cell at or up and right of the arena centre (the program's ceil(width / 2)).
        return (self.lights_per_side // 2 + 0.5) * self.light_pitch

    @property
    def box_apothem(self) -> float:
        if self.box_size_is == "apothem":
            return self.box_size
        return self.box_size * math.cos(math.pi / 6)

    @property
    def box_circumradius(self) -> float:
        return self.box_apothem / math.cos(math.pi / 6)

    @property
    def box_area(self) -> float:
        """Area of one regular hexagon: 2 sqrt(3) a^2 for apothem a."""
        return 2.0 * math.sqrt(3.0) * self.box_apothem**2

    def replace(self, **changes: Any) -> "Config":
        """A copy with some values changed (validated like the original).

        Changing ``profile`` takes every profiled value from the new profile,
        except those given in the same call.
        """
        unknown = set(changes) - set(param_names())
        if unknown:
            raise ConfigError(f"unknown parameter(s): {', '.join(sorted(unknown))}")
        values = {k: coerce(k, v) for k, v in changes.items()}
        if "profile" in values:
            for p in params():
                if p.profiled and p.name not in values:
                    values[p.name] = None  # resolved to the new profile's value
        return dataclasses.replace(self, **values)

    def differences_from_profile(self) -> dict[str, Any]:
        """Profiled values that differ from this config's profile (a user's overrides)."""
        return {p.name: getattr(self, p.name) for p in params()
                if p.profiled and getattr(self, p.name) != p.value_in(self.profile)}

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


# ---------------------------------------------------------------------------
# Introspection used by the CLI, config files and the GUI.


@dataclass(frozen=True)
class Param:
    name: str
    type: type
    default: Any
    help: str
    unit: str
    low: float | None
    high: float | None
    group: str
    choices: tuple[str, ...] | None
    rebuild: bool
    profiled: bool  # whether the profile sets it; then ``default`` is its authors-code value
    paper: Any  # its value in the paper-text profile (the default where not profiled)

    def value_in(self, profile: str) -> Any:
        return self.paper if profile == PAPER_TEXT else self.default


_TYPES = {"float": float, "int": int, "str": str, float: float, int: int, str: str}


def params() -> Iterator[Param]:
    """The declared parameters, in declaration order."""
    return iter(_param_table().values())


@functools.lru_cache(maxsize=None)
def _param_table() -> dict[str, Param]:
    return {p.name: p for p in _declared_params()}


def _declared_params() -> Iterator[Param]:
    for f in dataclasses.fields(Config):
        m = f.metadata
        default = m["profile_values"][AUTHORS_CODE] if m["profiled"] else f.default
        paper = m["profile_values"][PAPER_TEXT] if m["profiled"] else f.default
        yield Param(f.name, _TYPES[f.type], default, m["help"], m["unit"], m["low"], m["high"],
                    m["group"], m["choices"], m["rebuild"], m["profiled"], paper)


def param_names() -> list[str]:
    return [f.name for f in dataclasses.fields(Config)]


def param(name: str) -> Param:
    try:
        return _param_table()[name]
    except KeyError:
        raise ConfigError(f"unknown parameter {name!r}") from None


def coerce(name: str, value: Any) -> Any:
    """Convert a value (possibly a string from a CLI or form) to the parameter's type."""
    p = param(name)
    if isinstance(value, bool) and p.type is not str:
        raise ConfigError(f"{name}: expected a number, got {value!r}")
    try:
        if p.type is int:
            if isinstance(value, float) and not value.is_integer():
                raise ValueError
            number = float(value) if isinstance(value, str) else value
            if isinstance(number, float) and not number.is_integer():
                raise ValueError
            return int(number)
        return p.type(value)
    except (TypeError, ValueError, OverflowError):
        kind = {int: "a whole number", float: "a number", str: "text"}[p.type]
        raise ConfigError(f"{name}: expected {kind}, got {value!r}") from None


def check_value(name: str, value: Any) -> None:
    p = param(name)
    if p.type in (int, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{name}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{name}: must be finite, got {value!r}")
        if p.low is not None and value < p.low or p.high is not None and value > p.high:
            raise ConfigError(f"{name}: {value!r} is outside the allowed range [{p.low}, {p.high}]")
    elif p.choices and value not in p.choices:
        raise ConfigError(f"{name}: {value!r} is not one of {', '.join(p.choices)}")


def load_config_file(path: str | Path, base: Config | None = None) -> Config:
    """Read a TOML or JSON file of ``name = value`` pairs on top of ``base``.

    Unknown names are an error (a typo should not silently do nothing). Sections
    are allowed and flattened, so a file may group values as the panel does.
    """
    values = read_config_values(path)
    try:
        return (base or Config()).replace(**values)
    except ConfigError as exc:
        raise ConfigError(f"config file {path}: {exc}") from None


#: A config file larger than this is refused before it is parsed (no real one comes near).
MAX_CONFIG_BYTES = 1_000_000
#: Tables may group values (``[robots]``), and groups hold groups at most this deep.
MAX_CONFIG_DEPTH = 3
#: The keys that make a file with a ``config`` table a result record (a trial's JSON, ``run --json``).
_RESULT_KEYS = frozenset({"samples", "final", "fraction_in_goal"})


def read_config_values(path: str | Path) -> dict[str, Any]:
    """The ``name = value`` pairs of a TOML or JSON config file, checked
    (every name known, every value acceptable) but not applied. A result file
    (a trial's JSON, ``run --json``) is read as the configuration it records."""
    path = Path(path)
    text = _read_config_text(path)
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            data = tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"config file {path} is not valid {path.suffix.lstrip('.').upper() or 'TOML'}: {exc}") from None
    except RecursionError:
        raise ConfigError(f"config file {path} is nested too deeply to be a config file") from None
    if not isinstance(data, dict):
        raise ConfigError(f"config file {path} must hold a table of name = value pairs")
    try:
        flat = record_values(data["config"]) if _is_result_record(data) else _flatten(data)
        Config().replace(**flat)
    except ConfigError as exc:
        raise ConfigError(f"config file {path}: {exc}") from None
    return flat


def _read_config_text(path: Path) -> str:
    """The file's text, refused before parsing when it is not a regular file or too large."""
    try:
        if not path.is_file():
            raise ConfigError(f"config file {path} is not a regular file" if path.exists()
                              else f"cannot read config file {path}: no such file")
        with path.open("rb") as handle:
            data = handle.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"cannot read config file {path}: {exc.strerror or exc}") from None
    if len(data) > MAX_CONFIG_BYTES:
        raise ConfigError(f"config file {path} is larger than {MAX_CONFIG_BYTES // 1_000_000} MB; "
                          f"a config file is a few lines of name = value")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"config file {path} is not UTF-8 text") from None


def _is_result_record(data: dict[str, Any]) -> bool:
    return isinstance(data.get("config"), dict) and bool(_RESULT_KEYS & set(data))


def record_values(values: dict[str, Any]) -> dict[str, Any]:
    """The values of a configuration stored in a result file. Files written
    before profiles existed hold the model that is now ``paper-text`` and do
    not say so: they are read with that profile. An unknown name is an error."""
    values = _flatten(values)
    if "profile" not in values and "light_falloff" in values:
        values = {**values, "profile": PAPER_TEXT}
    return values


def config_from_record(values: dict[str, Any]) -> Config:
    """The :class:`Config` of a result file's ``config`` (see :func:`record_values`)."""
    return Config().replace(**record_values(values))


def _flatten(data: dict[str, Any], depth: int = 1) -> dict[str, Any]:
    """Groups' values as one table (``[robots] count`` is ``count``); too deep a nest is an error."""
    if depth > MAX_CONFIG_DEPTH:
        raise ConfigError(f"tables nested more than {MAX_CONFIG_DEPTH} deep; a config file is name = value pairs, "
                          f"optionally grouped in [tables]")
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, depth + 1))
        else:
            flat[str(key).replace("-", "_")] = value
    return flat


# The seven reference cases of the paper (SPEC §7).
CASES: dict[str, dict[str, Any]] = {
    "circle": dict(shape="circle"),
    "square": dict(shape="square"),
    "square-flare": dict(shape="square", flare=1.75),
    "square-flare-switch": dict(shape="square", flare=1.75, switch=0.25),
    "star": dict(shape="star"),
    "star-switch": dict(shape="star", switch=0.25),
    "star-switch-nocorners": dict(shape="star", switch=0.25, no_corners=0.5),
}

def case_config(name: str, base: Config | None = None) -> Config:
    if name not in CASES:
        raise ConfigError(f"unknown case {name!r}; the cases are: {', '.join(CASES)}")
    base = base or Config()
    return base.replace(**CASES[name])


def markdown_table() -> str:
    """The parameter table in docs/cli.md (a test keeps the two in step)."""
    rows = ["| flag | default (`authors-code`) | `paper-text` | unit | what it is |",
            "| --- | --- | --- | --- | --- |"]
    for p in params():
        paper = _cell(p.paper) if p.profiled else "same"
        rows.append(f"| `--{p.name.replace('_', '-')}` | {_cell(p.default)} | {paper} | {p.unit} | {p.help} |")
    return "\n".join(rows)


def _cell(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)
