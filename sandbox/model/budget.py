"""What a world will cost in memory, worked out from its settings before it is built, and the budget
it must fit (issue 54).

Every setting has a range, but some in-range combinations need more memory than any machine has:
light pitch 0.05 with field samples 64 asks for a 61 GB luminosity field, an arena of 2,000 m at
pitch 0.05 for 1.6 billion lights. So before a world is built its cost is estimated from its
:class:`~sandbox.model.config.Config` alone, term by term, and settings over the budget are refused
with one line that names the values to change and how far (:func:`refusal`). The check runs where
every configuration is made (``Config.__post_init__``) and again where every world is built
(``Simulation.reset``): the command line, config and design files and the page all pass through it.

The terms (bytes; the constants measured on Linux, CPython 3.11, pymunk 7, as peak resident memory
over a process that has imported the model, every light on):

* **light field**: the sampled luminosity field, float32, ``side^2`` samples, ``side`` as
  :class:`sandbox.model.lights._AxisLayout` lays it out (the arena's light cells and a window's worth
  of padding each side, times about ``field_samples + 3`` samples a cell), worked out exactly here
  without its arrays (:func:`field_side`), and the block each light adds (``block^2`` float32). All
  of it counts: a light program may light every light, and every page of the field is then written.
* **field block** (for a moment): the float64 arrays a light's block is computed from,
  :data:`KERNEL_BUILD` bytes a sample.
* **lights**: :data:`PER_LIGHT` bytes a light (the arena's cells: its centre, the patterns the
  controller, the field and a snapshot keep, the offset outline's distances to it).
* **bodies**: :data:`PER_ROBOT` and :data:`PER_BOX` bytes a body (pymunk's body and shape and their
  contacts, the state rows, the placement grid).
* **metrics**: :data:`PER_SAMPLE` bytes a sample a run of ``steps`` keeps.
* **goal** (for a moment, once the goal is known: :func:`world_cost`): growing a polygon by a
  distance, as the offset outline and chase do at every update, costs up to :data:`PER_VERTEX_PAIR`
  bytes a pair of its vertices (a comb's teeth all overlap once grown), and a notched goal's widths
  are measured on a grid :data:`WIDTH_SPACING` apart over it (:mod:`sandbox.model.thin`). A goal's
  vertices are bounded first (:data:`MAX_GOAL_VERTICES`, :func:`sandbox.model.goal.affordable_outline`).

Measured against the estimate (MB; the first four calibrate, the others check): field samples 64,
184 and 210; pitch 0.125 in a 256 m arena with range 0.5 and 1 sample (4.2 million lights), 748 and
774; 40,000 robots, 172 and 181; 40,000 boxes, 236 and 281; pitch 0.25, 68 and 84; pitch 0.5 with
32 samples, 220 and 250; 20,000 robots with 20,000 boxes, 181 and 231; pitch 0.1 with range 3.2,
179 and 185; the 300-vertex C of 0.84 m teeth of tests/model/test_budget.py on the offset outline, 57 and
53 (docs/security.md, "What a world may cost").

The budget (:func:`memory_budget`) is the ``PHOTOTAXIS_MEMORY_BUDGET`` environment variable when
set (``--memory-budget`` sets it for the command and its processes), else :func:`default_budget`:
a quarter of the machine's memory, at most 1 GB. A 4 GB laptop then holds a world and the world it
is compared with (1 GB each) beside the web server, its pages and the system; a bigger machine
raises it on purpose.
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import threading
from dataclasses import dataclass
from typing import Any, Callable, Iterator, NamedTuple, Protocol

from sandbox.model.config_error import ConfigError

MB, GB, GiB = 10**6, 10**9, 2**30
#: The environment variable that sets the budget (bytes, or a number with K, M, G or T, or a share of
#: the machine's memory such as ``50%``); ``--memory-budget`` sets it for a command and its processes.
BUDGET_VARIABLE = "PHOTOTAXIS_MEMORY_BUDGET"
#: The default budget is this share of the machine's memory ...
DEFAULT_SHARE = 0.25
#: ... and at most this.
DEFAULT_MOST = GB

#: Bytes per light: centres (16), the patterns of the controller, the field, the program's view and
#: a snapshot (8 each), the offset outline's distances, reach, least distance and sides (32), masks.
PER_LIGHT = 120
#: Bytes per sample of the kernel block while it is computed (float64 temporaries at their peak).
KERNEL_BUILD = 16
#: Bytes per robot and per box: pymunk's body and shape (with their Chipmunk structures), collision
#: pairs, the state and velocity rows, the placement grid; boxes are polygons and touch more.
PER_ROBOT = 3_500
PER_BOX = 6_000
#: Bytes per metrics sample a run keeps (sandbox.model.metrics.Sample and its list slot).
PER_SAMPLE = 240
#: The most vertices a goal keeps (sandbox.model.goal simplifies past it, or refuses): growing a goal
#: by a distance, which the offset outline and chase do at every update, costs as the square of its
#: vertices when its edges overlap once grown. Measured on the spiky C of tests/model/test_budget.py at
#: its worst distance: 300 vertices 0.22 s and 40 MB, 500 vertices 0.66 s and 140 MB, 1,000
#: vertices 5.0 s and 470 MB, 2,000 vertices 24 s and 2.2 GB.
MAX_GOAL_VERTICES = 300
#: Bytes per pair of a goal's vertices when it is grown (the 1,000-vertex spiky C: 470 MB).
PER_VERTEX_PAIR = 500
#: The grid a notched goal's widths are measured on (m, sandbox.model.thin), and bytes per point.
WIDTH_SPACING = 0.1
PER_WIDTH_POINT = 48



class Settings(Protocol):
    """What the budget reads of a :class:`~sandbox.model.config.Config`. Every Config checks itself
    against the budget as it is made (:func:`check_settings`), so this module is below config and does
    not import it: it reads these fields (and the knobs' by name), makes a variant with ``replace`` and
    the defaults with ``type(config)()``."""

    arena_size: float
    boxes: int
    construction_size: float
    field_samples: int
    light_pitch: float
    light_range: float
    light_window: str
    lights_per_side: int
    metrics_every: int
    robot_spawn_size: float
    robots: int
    steps: int

    def replace(self, **changes: Any) -> Settings: ...


#: The terms needed for a moment only, one at a time (see :class:`Cost`).
PASSING = frozenset({"field block", "goal"})


@dataclass(frozen=True)
class Cost:
    """A world's estimated memory, by what needs it (bytes). ``passing`` names the terms that are
    needed for a moment only (computing a light's block, growing the goal), one at a time: the
    total is what the world keeps plus the largest of them."""

    terms: dict
    passing: frozenset = frozenset()

    @property
    def total(self) -> float:
        kept = sum(v for k, v in self.terms.items() if k not in self.passing)
        return float(kept + max((self.terms.get(k, 0.0) for k in self.passing), default=0.0))

    def said(self) -> str:
        """The terms in words, largest first: 'light field 58 GB, lights 164 MB'."""
        shown = sorted(((v, k) for k, v in self.terms.items() if v >= 0.05 * self.total), reverse=True)
        return ", ".join(f"{name} {size_text(value)}" for value, name in shown)


# -- the terms ---------------------------------------------------------------------------------
def _strip_counts(config: Settings) -> list[int]:
    """How many intervals each strip of a light pitch has (sandbox.model.lights._AxisLayout)."""
    pitch = config.light_pitch
    target = pitch / config.field_samples
    cuts = _cuts(config)
    edges = [c - cuts[0] for c in cuts] + [pitch]
    return [max(1, math.ceil((hi - lo) / target - 1e-9)) for lo, hi in zip(edges[:-1], edges[1:])]


def _cuts(config: Settings) -> list[float]:
    """Where, within a light pitch, the set of lights in range changes (sandbox.model.lights._AxisLayout)."""
    pitch, reach = config.light_pitch, config.light_range
    cuts = {round((0.5 * pitch + reach) % pitch, 12), round((0.5 * pitch - reach) % pitch, 12)}
    if config.light_window == "cells":
        cuts.add(0.0)
    return sorted(cuts)


def _light_columns(config: Settings) -> tuple[int, int]:
    """(how many light columns reach a layout cell, the padding in cells each side): the kept
    ``light_offsets`` of :class:`sandbox.model.lights._AxisLayout` and its ``pad``, worked out on the
    strips' middles (which decide it) as intervals of columns, without the layout's arrays."""
    pitch, reach = config.light_pitch, config.light_range
    cuts = _cuts(config)
    origin = cuts[0]
    edges = [c - origin for c in cuts] + [pitch]
    t_max = int(math.ceil((reach + pitch) / pitch)) + 1
    low, high = -t_max, t_max
    if config.light_window == "cells":
        window = int(math.floor(reach / pitch + 1e-9))
        low, high = max(low, -window), min(high, window - 1)

    def reaches(t: int, mid: float) -> bool:  # the layout's test, with its operations in its order
        return abs(t * pitch + 0.5 * pitch - origin - mid) <= reach

    spans = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        mid = 0.5 * (lo + hi)
        first = math.ceil((mid - reach + origin - 0.5 * pitch) / pitch)
        last = math.floor((mid + reach + origin - 0.5 * pitch) / pitch)
        while first - 1 >= low and reaches(first - 1, mid):
            first -= 1
        while first <= last and not reaches(first, mid):
            first += 1
        while last + 1 <= high and reaches(last + 1, mid):
            last += 1
        while last >= first and not reaches(last, mid):
            last -= 1
        first, last = max(first, low), min(last, high)
        if first <= last:
            spans.append((first, last))
    if not spans:
        return 0, 1
    spans.sort()
    count, (start, end) = 0, spans[0]
    for a, b in spans[1:]:
        if a > end + 1:
            count += end - start + 1
            start, end = a, b
        else:
            end = max(end, b)
    count += end - start + 1
    return count, max(b for _, b in spans) + 1


class _Grid(NamedTuple):
    """What the field's layout depends on (Config's names: the functions above read either)."""

    light_pitch: float
    light_range: float
    field_samples: int
    light_window: str
    lights_per_side: int


def field_side(config: Settings) -> tuple[int, int]:
    """(samples per side of the luminosity field, samples per side of one light's block), as
    :class:`sandbox.model.lights._AxisLayout` makes them."""
    return _field_side(_Grid(config.light_pitch, config.light_range, config.field_samples, config.light_window,
                             config.lights_per_side))


@functools.lru_cache(maxsize=256)  # every Config is checked, and most share their light grid
def _field_side(config: _Grid) -> tuple[int, int]:
    per_cell = sum(count + 1 for count in _strip_counts(config))
    columns, pad = _light_columns(config)
    pitch, n = config.light_pitch, config.lights_per_side
    origin = _cuts(config)[0]
    first_cell = math.floor((0.0 - origin) / pitch)
    cells = math.floor((n * pitch - origin) / pitch) - first_cell + 1
    return (cells + 2 * pad) * per_cell, columns * per_cell


def field_bytes(config: Settings) -> float:
    """The luminosity field and the block each light adds to it (float32)."""
    side, block = field_side(config)
    return 4.0 * side**2 + 4.0 * block**2


def block_build_bytes(config: Settings) -> float:
    """The float64 arrays a light's block is computed from, for a moment."""
    return float(KERNEL_BUILD) * field_side(config)[1] ** 2


def light_bytes(config: Settings) -> float:
    return float(PER_LIGHT) * config.lights_per_side**2


def body_bytes(config: Settings) -> float:
    return float(PER_ROBOT) * config.robots + float(PER_BOX) * config.boxes


def metrics_bytes(config: Settings) -> float:
    return float(PER_SAMPLE) * (config.steps // config.metrics_every + 2)


def settings_cost(config: Settings) -> Cost:
    """The memory a world of these settings needs, before its goal is known (a circle adds nothing)."""
    return Cost({"light field": field_bytes(config), "field block": block_build_bytes(config),
                 "lights": light_bytes(config), "bodies": body_bytes(config), "metrics": metrics_bytes(config)},
                PASSING)


def goal_bytes(vertices: int, width: float = 0.0, height: float = 0.0) -> float:
    """A polygon goal of this many vertices whose fitted bounding box is ``width`` x ``height`` (m):
    grown by a distance (offset outline, chase) and its widths measured (a notched goal)."""
    grid = (width / WIDTH_SPACING + 1.0) * (height / WIDTH_SPACING + 1.0)
    return float(PER_VERTEX_PAIR) * vertices**2 + float(PER_WIDTH_POINT) * grid


def world_cost(config: Settings, vertices: int = 0, width: float = 0.0, height: float = 0.0) -> Cost:
    """The settings' cost with a polygon goal's (none for a circle)."""
    terms = dict(settings_cost(config).terms)
    terms["goal"] = goal_bytes(vertices, width, height) if vertices else 0.0
    return Cost(terms, PASSING)


# -- the budget --------------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def physical_memory() -> int | None:
    """The machine's memory (bytes), or None where the system does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def default_budget() -> int:
    """A quarter of the machine's memory, at most 1 GB (1 GB where the system does not say)."""
    physical = physical_memory()
    return DEFAULT_MOST if physical is None else int(min(DEFAULT_MOST, DEFAULT_SHARE * physical))


_UNITS = {"": 1, "B": 1, "K": 10**3, "KB": 10**3, "M": MB, "MB": MB, "G": GB, "GB": GB, "T": 10**12, "TB": 10**12,
          "KIB": 2**10, "MIB": 2**20, "GIB": GiB, "TIB": 2**40}


def parse_budget(text: str) -> int:
    """Bytes from '1.5G', '800M', '2GiB', '1000000000' or '50%' (of the machine's memory); a ValueError
    in one line otherwise."""
    raw = str(text).strip().upper().replace(" ", "")
    share = raw.endswith("%")
    number = raw[:-1] if share else raw.rstrip("KMGTIB")
    unit = "" if share else raw[len(number):]
    try:
        amount = float(number)
    except ValueError:
        amount = math.nan
    if not math.isfinite(amount) or amount < 0 or unit not in _UNITS:
        raise ValueError(f"memory budget {text!r}: give a size such as 2G, 800M or 50% (of the machine's memory)")
    physical = physical_memory()
    if share and physical is None:
        raise ValueError(f"memory budget {text!r}: this system does not say how much memory it has; give a size "
                         f"such as 2G")
    value = amount / 100.0 * physical if share else amount * _UNITS[unit]
    if value < 50 * MB:
        raise ValueError(f"memory budget {text!r}: at least 50M (a world of the paper's settings needs ~10 MB, "
                         f"a Python process with the model ~200 MB more)")
    if physical is not None and value > physical:
        raise ValueError(f"memory budget {text!r} is more than this machine's {size_text(physical)} of memory")
    return int(value)


def memory_budget() -> int:
    """The budget a world must fit (bytes): ``PHOTOTAXIS_MEMORY_BUDGET`` if set, else the default."""
    given = os.environ.get(BUDGET_VARIABLE, "").strip()
    if not given:
        return default_budget()
    try:
        return parse_budget(given)
    except ValueError as exc:
        raise ConfigError(f"{BUDGET_VARIABLE}: {exc}") from None


def set_budget(text: str) -> int:
    """Set the budget for this process and those it starts (``--memory-budget``); returns it (bytes)."""
    value = parse_budget(text)
    os.environ[BUDGET_VARIABLE] = str(value)
    return value


# -- the check and the one line ------------------------------------------------------------------
class OverBudget(ConfigError):
    """Settings (or a goal with them) that would need more memory than the budget."""


def check_settings(config: Settings) -> None:
    """Refuse settings whose world would not fit the budget (:class:`OverBudget`, one line)."""
    budget = memory_budget()
    cost = settings_cost(config)
    if cost.total > budget:
        raise OverBudget(refusal(config, cost, budget))


def size_text(size: float) -> str:
    """Bytes in words: '58 GB', '1.3 GB', '850 MB', '12 MB'."""
    for unit, name in ((10**12, "TB"), (GB, "GB"), (MB, "MB")):
        if size >= unit:
            value = size / unit
            return f"{value:.1f} {name}" if value < 10 else f"{value:,.0f} {name}"
    return f"{size / MB:.1f} MB"


@dataclass(frozen=True)
class Knob:
    """A setting the refusal may tell the user to change: its field, the way that costs less (+1
    raise, -1 lower) and the values worth suggesting, from the current one outwards."""

    name: str
    direction: int
    values: Callable[[Settings], Iterator[float]]


def _nice(low: float, high: float) -> list[float]:
    """Round numbers (1, 1.25, 1.6, 2, 2.5, 3.2, 4, 5, 6.4, 8 times a power of ten) from low to high."""
    found = []
    for power in range(math.floor(math.log10(max(low, 1e-9))) - 1, math.ceil(math.log10(max(high, 1e-9))) + 1):
        for m in (1, 1.25, 1.6, 2, 2.5, 3.2, 4, 5, 6.4, 8):
            v = round(m * 10.0**power, 10)
            if low <= v <= high:
                found.append(v)
    return sorted(set(found))


def _pitches(config: Settings) -> Iterator[float]:
    """Light pitches above the current one that divide the arena, roundest first at each size."""
    arena = config.arena_size
    for pitch in _nice(config.light_pitch * 1.0000001, 100.0):
        if abs(arena / pitch - round(arena / pitch)) <= 1e-6:
            yield pitch
    for cells in range(config.lights_per_side - 1, 0, -1):  # any pitch that divides the arena
        yield arena / cells


def _downwards_ints(name: str, least: int) -> Callable[[Settings], Iterator[float]]:
    def values(config: Settings) -> Iterator[float]:
        current = int(getattr(config, name))
        for value in _round_down_ints(current, least):
            yield value
    return values


def _round_down_ints(current: int, least: int) -> list[int]:
    """Whole numbers below ``current``, down to ``least``: every one below 100, two significant
    digits above (so a suggestion reads 52,000, not 52,317)."""
    out = []
    value = current - 1
    while value >= least:
        if value >= 100:
            digits = 10 ** (len(str(value)) - 2)
            value = value // digits * digits
        out.append(value)
        value -= 10 ** max(len(str(value)) - 2, 0) if value >= 100 else 1
    return out


def _downwards_floats(name: str, least: Callable[[Settings], float]) -> Callable[[Settings], Iterator[float]]:
    def values(config: Settings) -> Iterator[float]:
        return iter(reversed(_nice(least(config), getattr(config, name) * 0.9999999)))
    return values


def _arenas(config: Settings) -> Iterator[float]:
    """Smaller arenas that are a whole number of light pitches and hold the spawn square."""
    least = max(config.construction_size, config.robot_spawn_size)
    for arena in reversed(_nice(least, config.arena_size * 0.9999999)):
        if arena > config.construction_size and abs(arena / config.light_pitch - round(arena / config.light_pitch)) <= 1e-6:
            yield arena


KNOBS = {
    "light_pitch": Knob("light_pitch", +1, _pitches),
    "field_samples": Knob("field_samples", -1, _downwards_ints("field_samples", 1)),
    "light_range": Knob("light_range", -1, _downwards_floats("light_range", lambda c: c.light_pitch)),
    "arena_size": Knob("arena_size", -1, _arenas),
    "robots": Knob("robots", -1, _downwards_ints("robots", 0)),
    "boxes": Knob("boxes", -1, _downwards_ints("boxes", 0)),
    "steps": Knob("steps", -1, _downwards_ints("steps", 0)),
    "metrics_every": Knob("metrics_every", +1, lambda c: iter(_nice(c.metrics_every + 1, 10**9))),
}
#: Which settings each term grows with, the likeliest culprit first.
TERM_KNOBS = {
    "light field": ("light_pitch", "field_samples", "light_range", "arena_size"),
    "field block": ("light_pitch", "field_samples", "light_range"),
    "lights": ("light_pitch", "arena_size"),
    "bodies": ("robots", "boxes"),
    "metrics": ("metrics_every", "steps"),
}
#: How many fixes the refusal offers.
FIXES_SAID = 2


def refusal(config: Settings, cost: Cost, budget: float) -> str:
    """One line: which values need how much, over which budget, and what to change how far (the nearest
    value of each of the two most to blame that alone would fit)."""
    culprits = _culprits(config, cost)
    named = " with ".join(f"{_words(name)} {_value(getattr(config, name))}" for name in culprits[:2])
    fixes = _fixes(config, culprits, budget)
    line = f"{named} needs ~{size_text(cost.total)} ({cost.said()}), over the {size_text(budget)} budget"
    if fixes:
        return f"{line}: {' or '.join(fixes)}"
    return (f"{line}: {' and '.join(_verb(name) + ' ' + _words(name) for name in culprits[:2])} together, "
            f"or raise the budget (--memory-budget, docs/security.md)")


def goal_refusal(config: Settings, cost: Cost, budget: float, vertices: int) -> str:
    """One line for a goal that takes the world over the budget: what it and the settings need, and
    what would leave room for it."""
    goal = cost.terms["goal"]
    settings = settings_cost(config)
    room = budget - max(goal - settings.terms["field block"], 0.0)
    fixes = _fixes(config, _culprits(config, settings), room)
    advice = " or ".join(fixes + ["use a goal with fewer vertices"])
    return (f"the goal ({vertices:,} vertices, needing ~{size_text(goal)} as its outline grows) with these settings "
            f"needs ~{size_text(cost.total)} ({cost.said()}), over the {size_text(budget)} budget: {advice}")


def _culprits(config: Settings, cost: Cost) -> list[str]:
    """The settings to change, most to blame first: those of the costliest terms, the ones set away
    from their defaults before the others."""
    defaults = type(config)()
    names: list[str] = []
    for term in sorted(cost.terms, key=cost.terms.get, reverse=True):
        if cost.terms[term] < 0.25 * cost.total:
            continue
        knobs = TERM_KNOBS.get(term, ())
        changed = [k for k in knobs if getattr(config, k) != getattr(defaults, k)]
        names += [k for k in changed + [k for k in knobs if k not in changed] if k not in names]
    return names


def _fixes(config: Settings, culprits: list[str], room: float) -> list[str]:
    """'raise light pitch to at least 0.5', one per culprit that alone can bring the cost within
    ``room`` (at most :data:`FIXES_SAID`)."""
    fixes = []
    for name in culprits:
        value = _fitting_value(config, KNOBS[name], room)
        if value is not None:
            fixes.append(f"{_verb(name)} {_words(name)} to {'at least' if KNOBS[name].direction > 0 else 'at most'} "
                         f"{_value(value)}")
        if len(fixes) == FIXES_SAID:
            break
    return fixes


def _fitting_value(config: Settings, knob: Knob, room: float, tries: int = 400) -> float | None:
    """The nearest value of the knob (among those worth suggesting) whose settings fit ``room``, other
    settings as they are; None if none does."""
    for count, value in enumerate(knob.values(config)):
        if count >= tries:
            return None
        try:
            candidate = _unchecked(config, knob.name, value)
        except ConfigError:
            continue
        if settings_cost(candidate).total <= room:
            return value
    return None


def _unchecked(config: Settings, name: str, value: float) -> Settings:
    """``config`` with one value changed, checked like any other but for the budget."""
    with unchecked_budget():
        return config.replace(**{name: value})


_trying = threading.local()


@contextlib.contextmanager
def unchecked_budget() -> Iterator[None]:
    """Within it, on this thread, Config checks everything but the budget (to try the values a refusal
    may suggest)."""
    _trying.depth = getattr(_trying, "depth", 0) + 1
    try:
        yield
    finally:
        _trying.depth -= 1


def budget_checked() -> bool:
    """Whether Config checks the budget now (not while a refusal tries values on this thread)."""
    return getattr(_trying, "depth", 0) == 0


def _words(name: str) -> str:
    return name.replace("_", " ")


def _verb(name: str) -> str:
    return "raise" if KNOBS[name].direction > 0 else "lower"


def _value(value: float) -> str:
    if isinstance(value, int) or float(value).is_integer():
        return f"{int(value):,}"
    return f"{value:g}"
