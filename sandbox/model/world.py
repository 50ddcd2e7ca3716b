"""The pymunk world (SPEC §2): arena wall, box-only construction wall, robots and boxes.

State moves between pymunk and numpy in bulk, robots first, then boxes, then
the space's static body; no per-body Python loop runs per step. It is read
straight from Chipmunk's memory in one compiled loop where that is checked
to hold (:mod:`sandbox.model.body_memory`), else through ``pymunk.batch``;
velocities are written through ``pymunk.batch`` or Chipmunk's setters.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import pymunk
import pymunk.batch as batch

from sandbox.model import body_memory, kernels, pymunk_seam, undamped
from sandbox.model.config import Config, ConfigError
from sandbox.model.goal import Goal
from sandbox.shapes import geometry

# Collision categories: the construction wall only meets boxes.
ROBOT, BOX, OUTER_WALL, CONSTRUCTION_WALL = 1, 2, 4, 8
# Walls are thick segments whose inner face is on the boundary. With thin
# (0.05 m) walls, robots squeezing boxes against the construction wall
# pushed one through about every 700,000 steps (2 boxes in a 1,000,000-step
# run, 1 in 14 paper trials); to get out now a box's centre must be pushed
# 0.75 m (half the wall plus its own apothem) into the wall.
WALL_RADIUS = 0.5

_POSE = batch.BodyFields.POSITION | batch.BodyFields.ANGLE | batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY
_POSE_AND_ID = _POSE | batch.BodyFields.BODY_ID
_VELOCITY = batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY


def hexagon(circumradius: float) -> list[tuple[float, float]]:
    return [(circumradius * math.cos(k * math.pi / 3), circumradius * math.sin(k * math.pi / 3)) for k in range(6)]


def square_corners(centre: float, half: float) -> list[tuple[float, float]]:
    return [(centre - half, centre - half), (centre + half, centre - half),
            (centre + half, centre + half), (centre - half, centre + half)]


def packed_in_goal(config: Config, goal: Goal) -> np.ndarray:
    """``config.boxes`` centres on a hexagonal tiling (each box's flats facing its six neighbours
    at angle 0, skins 1 mm apart), filled from deepest inside the goal outward, within the construction
    area: the goal built as densely as the boxes tile, its overflow a thin rim around it."""
    cfg = config
    pitch = 2.0 * (cfg.box_apothem + cfg.box_skin) + 0.001
    c, half = cfg.centre, cfg.construction_size / 2.0 - cfg.box_circumradius - cfg.box_skin - 0.01
    # Neighbours lie across the flats of a hexagon with a vertex at angle 0: at 30, 90, 150... degrees.
    a, b = pitch * np.array([math.cos(math.pi / 6), math.sin(math.pi / 6)]), pitch * np.array([0.0, 1.0])
    reach = int(math.ceil(2 * half / (pitch * math.cos(math.pi / 6)))) + 1
    i, j = (k.reshape(-1, 1) for k in np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1)))
    points = goal.centre + i * a + j * b
    points = points[np.all(np.abs(points - c) <= half, axis=1)]
    if len(points) < cfg.boxes:
        raise ConfigError(f"box_start 'packed': {cfg.boxes:,} boxes do not tile the construction area "
                          f"({len(points):,} places)")
    depth = np.where(goal.contains(points), -geometry.distance_to_outline(points, goal.outline()),
                     goal.distance(points))
    return points[np.argsort(depth, kind="stable")[:cfg.boxes]]


def sample_separated(rng: np.random.Generator, n: int, low: float, high: float, min_gap: float,
                     reject=None, max_tries: int = 200, progress=None) -> np.ndarray:
    """Uniform random points in the square [low, high]^2, never where
    ``reject(x, y)`` says no, and at least ``min_gap`` apart where possible:
    a point that finds no free spot in ``max_tries`` tries is placed at the
    last allowed spot tried (the physics pushes it clear). ``progress(k)`` is
    told how many points are placed, now and then (it may raise to stop).

    Each try is checked on plain floats: a crowded start (3,000 robots) makes
    hundreds of thousands of tries, and a NumPy call per try cost 3/4 of the
    time to build the world."""
    cell = max(min_gap, 1e-9)
    gap2 = min_gap**2
    grid: dict[tuple[int, int], list[tuple[float, float]]] = {}
    out = np.empty((n, 2))

    def free(x: float, y: float) -> bool:
        gx, gy = int(x // cell), int(y // cell)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for qx, qy in grid.get((gx + dx, gy + dy), ()):
                    if (qx - x) ** 2 + (qy - y) ** 2 < gap2:
                        return False
        return True

    for k in range(n):
        if progress is not None and k % 64 == 0:
            progress(k)
        allowed = None
        for _ in range(max_tries):
            x, y = rng.uniform(low, high, size=2).tolist()
            if reject is not None and reject(x, y):
                continue
            allowed = (x, y)
            if free(x, y):
                break
        while allowed is None:  # every try was in a forbidden place: keep drawing until one is not
            x, y = rng.uniform(low, high, size=2).tolist()
            if not reject(x, y):
                allowed = (x, y)
        out[k] = allowed
        grid.setdefault((int(allowed[0] // cell), int(allowed[1] // cell)), []).append(allowed)
    return out


class World:
    """The physics world and bulk access to its bodies' state."""

    def __init__(self, config: Config, rng: np.random.Generator, progress: Callable[[float], None] | None = None,
                 goal: Goal | None = None):
        """``progress(fraction)`` hears how far the placement of bodies has got (it may raise to stop).
        ``goal`` is where ``config.box_start == 'packed'`` tiles the boxes (required then)."""
        if config.box_start == "packed" and goal is None:
            raise ValueError("box_start 'packed' needs the goal to pack the boxes in")
        pymunk_seam.check()  # (once a process) one line on a pymunk that lacks what the model uses
        self.config = config
        self.n_robots, self.n_boxes = config.robots, config.boxes
        total = max(1, self.n_robots + self.n_boxes)
        self._progress = (lambda placed: progress(placed / total)) if progress else None
        self.space = self._make_space()
        self._add_walls()
        self._add_robots(rng)
        self._add_boxes(rng, goal)
        # Damping is applied by the space to every body. With the 'continuous'
        # motor a robot's commanded velocity is divided by the per-step damping
        # factor to arrive unchanged (see push_velocities); with 'set-once'
        # robots are undamped, as in Box2D where only the boxes have damping.
        self.damping_per_step = self.space.damping ** config.dt
        if config.motor == "set-once":
            for body in self.robot_bodies:
                undamped.make_undamped(body)
        self._buffer = batch.Buffer()
        # pymunk.batch lists awake bodies in the order they were added, then
        # the space's static body (holding the walls), then sleeping bodies
        # by group: with sleeping on, rows are found from the bodies' ids.
        bodies = [*self.robot_bodies, *self.box_bodies, self.space.static_body]
        ids = np.array([b.id for b in bodies], dtype=np.uintp)
        self._id_order = np.argsort(ids)
        self._sorted_ids = ids[self._id_order]
        #: Row of :attr:`state` of each body pymunk.batch listed in the last read, and its id
        #: (0, no body's, until the first read).
        self._rows = np.arange(len(bodies))
        self._last_ids = np.zeros(len(bodies), dtype=np.uintp)
        self._robot_pointers = [pymunk_seam.body_pointer(b) for b in self.robot_bodies]
        self._robot_addresses = body_memory.addresses(self.robot_bodies)
        self.state = np.zeros((self.n_robots + self.n_boxes + 1, 6))
        #: Velocities for the next step, (vx, vy, w) per row of :attr:`state`;
        #: pymunk reads them straight from this array's memory.
        self.velocities = np.zeros((len(self.state), 3))
        self._velocity_buffer = batch.Buffer()
        self._velocity_buffer.set_float_buf(self.velocities.reshape(-1))
        self._velocity_order = np.zeros_like(self.velocities)  # velocities in pymunk.batch's order
        self._read_batch()
        #: Each body's ``cpBody`` address, row by row, where the state is read from memory
        #: (see :mod:`sandbox.model.body_memory`); None: read through pymunk.batch. The 'continuous'
        #: motor pushes velocities through the batch, in the batch's order, which only its read keeps.
        self._addresses = self._memory_addresses(bodies) if config.motor == "set-once" else None

    # -- construction -----------------------------------------------------
    def _make_space(self) -> pymunk.Space:
        cfg = self.config
        space = pymunk.Space(threaded=cfg.threads > 1)
        if cfg.threads > 1:
            space.threads = cfg.threads
        space.gravity = (0.0, 0.0)
        space.iterations = cfg.iterations
        space.collision_slop = cfg.collision_slop
        space.damping = box_damping_per_second(cfg)
        if cfg.sleep_time > 0:
            space.sleep_time_threshold = cfg.sleep_time
            space.idle_speed_threshold = cfg.idle_speed
        return space

    def _add_walls(self) -> None:
        cfg = self.config
        half = cfg.arena_size / 2.0
        self._add_square_wall(half, half + WALL_RADIUS, pymunk.ShapeFilter(categories=OUTER_WALL))
        box_only = pymunk.ShapeFilter(categories=CONSTRUCTION_WALL, mask=BOX)
        self._add_square_wall(cfg.centre, cfg.construction_size / 2.0 + WALL_RADIUS, box_only)

    def _add_square_wall(self, centre: float, half: float, shape_filter: pymunk.ShapeFilter) -> None:
        body = self.space.static_body
        corners = square_corners(centre, half)
        for a, b in zip(corners, corners[1:] + corners[:1]):
            seg = pymunk.Segment(body, a, b, WALL_RADIUS)
            seg.friction = self.config.wall_friction
            seg.elasticity = 0.0
            seg.filter = shape_filter
            self.space.add(seg)

    def _add_robots(self, rng: np.random.Generator) -> None:
        cfg = self.config
        c, r = cfg.centre, cfg.robot_radius
        low, high = c - cfg.robot_spawn_size / 2.0 + r, c + cfg.robot_spawn_size / 2.0 - r
        keep_out = cfg.construction_size / 2.0 + r

        cx = cy = float(c)  # the centre is (c, c)

        def inside_construction(x: float, y: float) -> bool:
            return abs(x - cx) < keep_out and abs(y - cy) < keep_out

        positions = sample_separated(rng, self.n_robots, low, high, 2 * r, reject=inside_construction,
                                     progress=self._progress)
        headings = rng.uniform(-math.pi, math.pi, self.n_robots)
        robot_filter = pymunk.ShapeFilter(categories=ROBOT, mask=pymunk.ShapeFilter.ALL_MASKS() ^ CONSTRUCTION_WALL)
        self.robot_bodies = self._add_bodies(positions, headings, lambda body: pymunk.Circle(body, r),
                                             cfg.robot_density, cfg.robot_friction, cfg.robot_elasticity,
                                             robot_filter)

    def _add_boxes(self, rng: np.random.Generator, goal: Goal | None) -> None:
        cfg = self.config
        c, half = cfg.centre, cfg.construction_size / 2.0
        margin = cfg.box_circumradius + 0.01  # clear of the wall's inner face
        placed = (lambda k: self._progress(self.n_robots + k)) if self._progress else None
        positions = sample_separated(rng, self.n_boxes, c - half + margin, c + half - margin, 2 * cfg.box_apothem,
                                     progress=placed)
        angles = rng.uniform(0.0, math.pi / 3, self.n_boxes)
        if cfg.box_start == "packed":
            # Drawn above all the same, so a seed's robots and command phases do not depend on the start.
            positions, angles = packed_in_goal(cfg, goal), np.zeros(self.n_boxes)
        vertices = hexagon(cfg.box_circumradius)
        self.box_bodies = self._add_bodies(positions, angles,
                                           lambda body: pymunk.Poly(body, vertices, radius=cfg.box_skin),
                                           cfg.box_density, cfg.box_friction, cfg.box_elasticity,
                                           pymunk.ShapeFilter(categories=BOX))

    def _add_bodies(self, positions: np.ndarray, angles: np.ndarray, make_shape, density: float, friction: float,
                    elasticity: float, shape_filter: pymunk.ShapeFilter) -> list[pymunk.Body]:
        bodies = []
        for p, a in zip(positions, angles):
            body = pymunk.Body()
            body.position = tuple(p)
            body.angle = float(a)
            shape = make_shape(body)
            shape.density = density
            shape.friction = friction
            shape.elasticity = elasticity
            shape.filter = shape_filter
            self.space.add(body, shape)
            bodies.append(body)
        return bodies

    # -- bulk state -------------------------------------------------------
    def _memory_addresses(self, bodies: list[pymunk.Body]) -> np.ndarray | None:
        """The bodies' addresses if reading them from memory gives, bit for bit, what pymunk.batch
        just read (checked once per world: the layout is not pymunk's API)."""
        if not body_memory.layout_holds():
            return None
        addresses = body_memory.addresses(bodies)
        from_memory = np.empty_like(self.state)
        body_memory.read_rows(addresses, from_memory)
        return addresses if np.array_equal(from_memory.view(np.uint64), self.state.view(np.uint64)) else None

    def read(self) -> np.ndarray:
        """Refresh :attr:`state`: rows (x, y, angle, vx, vy, w): robots, boxes, static body."""
        if self._addresses is not None:
            body_memory.read_rows(self._addresses, self.state)
            return self.state
        return self._read_batch()

    def _read_batch(self) -> np.ndarray:
        self._buffer.clear()
        if self.config.sleep_time <= 0:
            batch.get_space_bodies(self.space, _POSE, self._buffer)
            self.state[:] = np.frombuffer(self._buffer.float_buf()).reshape(self.state.shape)
            return self.state
        batch.get_space_bodies(self.space, _POSE_AND_ID, self._buffer)
        ids = np.frombuffer(self._buffer.int_buf(), dtype=np.uintp)
        rows_read = np.frombuffer(self._buffer.float_buf()).reshape(self.state.shape)
        kernels.scatter_by_id(ids, rows_read, self._last_ids, self._rows, self._sorted_ids, self._id_order,
                              self.state)
        return self.state

    def push_velocities(self) -> None:
        """Hand :attr:`velocities` (one (vx, vy, w) row per body, in :attr:`state`'s
        order) to pymunk in one call. Robots' rows must already be divided
        by :attr:`damping_per_step`; other rows should hold their current values.
        (This wakes every body: the 'continuous' motor keeps everything awake.)"""
        if self.config.sleep_time > 0:
            self._velocity_order[:] = self.velocities[self._rows]
            self._velocity_buffer.set_float_buf(self._velocity_order.reshape(-1))
        batch.set_space_bodies(self.space, _VELOCITY, self._velocity_buffer)

    def set_robot_velocities(self, writes: np.ndarray, count: int) -> None:
        """Set the velocity of a few robots: ``writes[:count]`` rows are
        (robot index, vx, vy, angular velocity). Straight through Chipmunk's
        setters (which wake the body, as Box2D's do for a moving one), called
        from compiled code where :mod:`body_memory` can (see its docstring),
        else through cffi (a third of the cost of pymunk's properties)."""
        if body_memory.SETTERS is not None:
            body_memory.set_velocities(self._robot_addresses, writes, count, *body_memory.SETTERS)
            return
        pointers = self._robot_pointers
        set_velocity, set_angular_velocity = pymunk_seam.velocity_setters()
        for index, vx, vy, w in writes[:count].tolist():
            body = pointers[int(index)]
            set_velocity(body, (vx, vy))
            set_angular_velocity(body, w)

    def step(self) -> None:
        self.space.step(self.config.dt)


def box_damping_per_second(config: Config) -> float:
    """pymunk's ``Space.damping``: the fraction of velocity a body keeps after
    one second, chosen so that one step keeps ``exp(-c dt)`` (exponential)
    or, as Box2D integrates damping, ``1 / (1 + c dt)``."""
    c, dt = config.box_damping, config.dt
    if config.box_damping_model == "exponential":
        return math.exp(-c)
    return (1.0 / (1.0 + c * dt)) ** (1.0 / dt)
