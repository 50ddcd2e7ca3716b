"""Every parameter of the model, declared once.

Each field of :class:`Config` carries its default, unit, allowed range, help
text and group in its metadata. The CLI flags, the config-file loader, the
browser panel and the result files are all generated from these declarations
(see :func:`params`), so a new parameter needs to be added here only.
Defaults follow ``SPEC.md``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib


class ConfigError(ValueError):
    """A configuration value or file a user gave is not acceptable."""


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
) -> Any:
    """Declare one parameter. ``rebuild`` says whether a change needs a reset."""
    meta = dict(help=help, unit=unit, low=low, high=high, group=group, choices=choices, rebuild=rebuild)
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class Config:
    """The full, typed configuration of one simulation run."""

    # --- arena (SPEC §2) -------------------------------------------------
    arena_size: float = _param(64.0, "side of the square arena", unit="m", low=2.0, high=2000.0, group="arena")
    construction_size: float = _param(
        16.0, "side of the central construction area whose wall stops boxes but not robots",
        unit="m", low=1.0, high=2000.0, group="arena")
    robot_spawn_size: float = _param(
        32.0, "side of the central square robots start in (outside the construction area)",
        unit="m", low=1.0, high=2000.0, group="arena")
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
        "apothem", "what box_size measures: 'apothem' (paper text) or 'circumradius' (authors' code)",
        group="bodies", choices=("apothem", "circumradius"))
    box_density: float = _param(0.5, "box density", unit="kg/m^2", low=1e-3, high=1e4, group="bodies")
    box_friction: float = _param(1.0, "box friction coefficient", low=0.0, high=10.0, group="bodies")
    box_elasticity: float = _param(0.1, "box restitution", low=0.0, high=1.0, group="bodies")
    box_damping: float = _param(
        10.0, "linear and angular damping of boxes (the box slides only while pushed)",
        unit="1/s", low=0.0, high=1000.0, group="bodies")

    # --- light grid (SPEC §3) --------------------------------------------
    light_pitch: float = _param(1.0, "spacing of the overhead lights", unit="m", low=0.05, high=100.0, group="lights")
    light_height: float = _param(1.0, "height of the lights above the floor", unit="m", low=0.01, high=100.0, group="lights")
    light_falloff: float = _param(
        1.0, "falloff exponent k in B = I / d^k (paper 1, authors' code 2)", low=0.0, high=6.0, group="lights")
    light_range: float = _param(
        12.8, "lights further than this in x or y do not reach a point", unit="m", low=0.1, high=2000.0, group="lights")
    light_intensity: float = _param(1.0, "intensity of a light that is on", low=0.0, high=1000.0, group="lights")
    field_samples: int = _param(
        6, "luminosity-field samples per light pitch, at least (more is finer and slower to rebuild)",
        low=1, high=64, group="lights")

    # --- robots (SPEC §4) ------------------------------------------------
    sensor_offset: float = _param(
        0.1, "distance of each photocell from the robot's centre", unit="m", low=0.0, high=10.0, group="robot")
    k_drive: float = _param(5.0, "forward speed gain: v = k_drive (front - back)", low=0.0, high=1e4, group="robot", rebuild=False)
    k_turn: float = _param(20.0, "turn rate gain: w = k_turn (left - right)", low=0.0, high=1e4, group="robot", rebuild=False)
    command_period: int = _param(
        50, "steps a robot holds its command before it reads its photocells again",
        unit="steps", low=1, high=100_000, group="robot")
    eta_in: float = _param(0.4, "charge gained per unit of luminosity per step", low=0.0, high=1e4, group="robot", rebuild=False)
    metabolic: float = _param(0.01, "charge spent per step just to live", low=0.0, high=1e4, group="robot", rebuild=False)
    eta_out: float = _param(0.1, "charge spent per unit of |v| + |w| per step", low=0.0, high=1e4, group="robot", rebuild=False)
    capacity: float = _param(20.0, "largest charge a robot stores", low=0.0, high=1e6, group="robot", rebuild=False)
    start_charge: float = _param(0.0, "charge of every robot at reset", low=0.0, high=1e6, group="robot")

    # --- controller (SPEC §5) --------------------------------------------
    shape: str = _param(
        "circle", "goal shape: 'circle', a name in shapes/, or a polygon file", group="controller", rebuild=False)
    update_every: int = _param(100, "steps between controller updates", unit="steps", low=1, high=1_000_000, group="controller", rebuild=False)
    scale_rate: float = _param(
        0.975, "outline scale factor per update while contracting (its inverse while dilating)",
        low=0.5, high=0.9999, group="controller", rebuild=False)
    hold_steps: int = _param(
        25, "world steps the outline holds at its smallest size (the paper's t)",
        unit="steps", low=0, high=1_000_000, group="controller", rebuild=False)
    band: float = _param(
        0.5, "a light is on when its centre is within this distance of the outline",
        unit="m", low=0.0, high=100.0, group="controller", rebuild=False)
    circle_max: float = _param(
        0.75, "largest circle radius, as a fraction of half the arena width", low=0.05, high=1.0, group="controller", rebuild=False)
    polygon_max_area: float = _param(
        0.5, "largest polygon outline, as a fraction of the arena's area (capped to stay inside)",
        low=0.01, high=1.0, group="controller", rebuild=False)
    flare: float = _param(
        0.0, "flare amount f (0 = off; 1.75 when switched on): corners pushed out by max(1, 90 f / angle)",
        low=0.0, high=10.0, group="strategies", rebuild=False)
    switch: float = _param(
        0.0, "switch to a circle this fraction of the way from smallest to largest (0 = off; 0.25 when on)",
        low=0.0, high=1.0, group="strategies", rebuild=False)
    no_corners: float = _param(
        0.0, "fraction of band lights nearest convex corners that stay off (0 = off; 0.5 when on)",
        low=0.0, high=1.0, group="strategies", rebuild=False)

    # --- run -------------------------------------------------------------
    steps: int = _param(100_000, "world steps in a run", unit="steps", low=0, high=10**9, group="run", rebuild=False)
    seed: int = _param(0, "random seed: the same seed and configuration give the same run", low=0, high=2**63 - 1, group="run")
    metrics_every: int = _param(1000, "steps between metric samples", unit="steps", low=1, high=10**9, group="run", rebuild=False)

    # --- physics engine tuning (not part of the model) -------------------
    iterations: int = _param(10, "pymunk solver iterations per step", low=1, high=100, group="physics")
    threads: int = _param(1, "pymunk solver threads (1 or 2; 2 uses pymunk's threaded solver)", low=1, high=2, group="physics")
    collision_slop: float = _param(0.01, "allowed overlap between shapes", unit="m", low=0.0, high=1.0, group="physics")

    def __post_init__(self) -> None:
        for p in dataclasses.fields(self):
            check_value(p.name, getattr(self, p.name))
        if self.construction_size >= self.arena_size:
            raise ConfigError("construction_size must be smaller than arena_size")
        if self.robot_spawn_size > self.arena_size:
            raise ConfigError("robot_spawn_size must not exceed arena_size")
        cells = self.arena_size / self.light_pitch
        if abs(cells - round(cells)) > 1e-6:
            raise ConfigError(
                f"arena_size ({self.arena_size}) must be a whole number of light_pitch ({self.light_pitch})")

    # Derived quantities -------------------------------------------------
    @property
    def lights_per_side(self) -> int:
        return int(round(self.arena_size / self.light_pitch))

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
        """A copy with some values changed (validated like the original)."""
        unknown = set(changes) - set(param_names())
        if unknown:
            raise ConfigError(f"unknown parameter(s): {', '.join(sorted(unknown))}")
        return dataclasses.replace(self, **{k: coerce(k, v) for k, v in changes.items()})

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


_TYPES = {"float": float, "int": int, "str": str, float: float, int: int, str: str}


def params() -> Iterator[Param]:
    """The declared parameters, in declaration order."""
    for f in dataclasses.fields(Config):
        m = f.metadata
        yield Param(f.name, _TYPES[f.type], f.default, m["help"], m["unit"], m["low"], m["high"],
                    m["group"], m["choices"], m["rebuild"])


def param_names() -> list[str]:
    return [f.name for f in dataclasses.fields(Config)]


def param(name: str) -> Param:
    for p in params():
        if p.name == name:
            return p
    raise ConfigError(f"unknown parameter {name!r}")


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
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read config file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"config file {path} is not UTF-8 text") from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            data = tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"config file {path} is not valid {path.suffix.lstrip('.').upper() or 'TOML'}: {exc}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"config file {path} must hold a table of name = value pairs")
    flat = _flatten(data)
    # A result file stores the configuration under "config": accept it as is.
    if "config" in data and isinstance(data["config"], dict):
        flat = _flatten(data["config"])
    try:
        return (base or Config()).replace(**flat)
    except ConfigError as exc:
        raise ConfigError(f"config file {path}: {exc}") from None


def _flatten(data: dict[str, Any]) -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            flat.update(_flatten(value))
        else:
            flat[key.replace("-", "_")] = value
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

#: The value a strategy takes when it is switched on without an amount.
STRATEGY_DEFAULTS = {"flare": 1.75, "switch": 0.25, "no_corners": 0.5}


def case_config(name: str, base: Config | None = None) -> Config:
    if name not in CASES:
        raise ConfigError(f"unknown case {name!r}; the cases are: {', '.join(CASES)}")
    base = base or Config()
    return base.replace(**CASES[name])


def markdown_table() -> str:
    """The parameter table in README.md (a test keeps the two in step)."""
    rows = ["| flag | default | unit | what it is |", "| --- | --- | --- | --- |"]
    for p in params():
        default = f"{p.default:.6g}" if isinstance(p.default, float) else str(p.default)
        rows.append(f"| `--{p.name.replace('_', '-')}` | {default} | {p.unit} | {p.help} |")
    return "\n".join(rows)
