"""Where the robots are, side by side of the goal, cycle by cycle; and the mirror test.

A lab script for the notched README's section *Why the K loses* (issue 42),
not part of the sandbox. Two uses, each on one shape and seed::

    python static/shapes/notched/diagnose_sides.py count static/shapes/notched/own/K.txt --seed 0
    python static/shapes/notched/diagnose_sides.py mirror static/shapes/notched/own/K.txt --seeds 0 1 2 3

``count`` prints, every 1,000 steps, the band's distance and phase and how
many robots lie beside each side of the goal's bounding box (L and R within
its height, B below it, T above it, I inside it), and the boxes outside the
goal to its left.

``mirror`` is a diagnostic, not a light program: at each turn of the band
from dilating to contracting it mirrors the robots across the goal's
vertical axis (only those outside the construction area whose mirror image
is outside it too), then prints each trial's fraction at the last step and
its mean over the last fifth. ``--no-mirror`` runs the same loop untouched
(it gives the default's trials bit for bit). Mirroring moves pymunk bodies
by hand, which no light can do: it only tells whether the robots' side
matters.

``gather`` is a light program (the robots move only by the light): at each
such turn the paper's controller is paused for ``--hold`` steps while only
the band's lights beside the chosen sides of the goal's bounding box stay
lit (``--sides``: any of L, R, B, T), so robots within reach of them drive
there; then the band comes back where it was and the controller goes on::

    python static/shapes/notched/diagnose_sides.py gather static/shapes/notched/own/K.txt --sides L --hold 3000

``mouths`` prints each notch's mouth direction (from the notch's centroid to
its mouth's), their mean, and the side a first rule gathers beside: the
bounding box's side opposite the mean, when the mean is at least
:data:`MEAN_AT_LEAST` long.
"""

from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import shapely

from sandbox.model import gather, notches
from sandbox.model.config import Config
from sandbox.model.lights import light_centres
from sandbox.model.simulation import Simulation
from sandbox.shapes import ShapeError, shape_vertices


def sides(robots: np.ndarray, bounds: tuple[float, float, float, float]) -> dict[str, int]:
    """How many robots lie beside each side of the goal's bounding box (left and right within its
    height, below and above it across the whole width), or inside it."""
    out = gather.beyond(robots, bounds)
    level = ~out["B"] & ~out["T"]
    return {"L": int((out["L"] & level).sum()), "R": int((out["R"] & level).sum()),
            "B": int(out["B"].sum()), "T": int(out["T"].sum()),
            "I": int((~out["L"] & ~out["R"] & level).sum())}


#: The trials below ran before the model gathered (``Config.gather``, sandbox/model/gather.py, which came of
#: them): off, they reproduce the README's numbers.
GATHER = "off"

#: The first rule gathers only when the notches' mean mouth direction is at least this long.
MEAN_AT_LEAST = 0.3


def mouths(shape: str) -> None:
    """Each notch's mouth direction, their mean, and the side the first rule gathers beside."""
    sim = Simulation(Config(shape=shape, gather=GATHER))
    directions = gather.mouth_directions(sim.goal.vertices, tuple(notches.notch_polygons(sim.goal.vertices)))
    mean = np.mean(directions, axis=0) if directions else np.zeros(2)
    side = gather.faced_side(-mean) if np.hypot(*mean) >= MEAN_AT_LEAST else "none"
    print(f"mouths {np.round(directions, 2).tolist()}, mean {np.round(mean, 2).tolist()} "
          f"({np.hypot(*mean):.2f} long): gather beside {side}")


def count(shape: str, seed: int, steps: int) -> None:
    sim = Simulation(Config(shape=shape, seed=seed, gather=GATHER))
    goal = shapely.Polygon(sim.goal.vertices)
    while sim.steps_done < steps:
        sim.step(1000)
        boxes = sim.box_positions
        outside = ~shapely.contains_xy(goal, boxes[:, 0], boxes[:, 1])
        state = sim.controller.state
        print(sim.steps_done, f"{sim.measure().fraction_in_goal:.3f}", f"band {state.scale:.2f} m", state.phase,
              "robots", sides(sim.robot_positions, goal.bounds),
              "boxes outside to the left", int((outside & (boxes[:, 0] < goal.bounds[0])).sum()), flush=True)


def mirror_outside(sim: Simulation, axis_x: float) -> int:
    """Mirror the robots outside the construction area across x = axis_x (those whose image is outside
    it too); how many moved."""
    centre, half = sim.config.centre, sim.config.construction_size / 2 + sim.config.robot_radius

    def outside(x: float, y: float) -> bool:
        return abs(x - centre) > half or abs(y - centre) > half

    moved = 0
    for body in sim.world.robot_bodies:
        x, y = body.position
        if outside(x, y) and outside(2 * axis_x - x, y):
            body.position = (2 * axis_x - x, y)
            body.angle = math.pi - body.angle
            moved += 1
    sim.world.read()
    return moved


def beside(sim: Simulation, chosen: str) -> np.ndarray:
    """Which lights lie beyond the goal's bounding box on the chosen sides (any of L, R, B, T), shaped as
    the controller's pattern."""
    centres = light_centres(sim.config).reshape(-1, 2)
    keep = gather.beyond_sides(centres, shapely.Polygon(sim.goal.vertices).bounds, chosen)
    return keep.reshape(sim.controller.intensities.shape)


def gather_at_turns(sim: Simulation, chosen: str, hold: int) -> dict[str, int]:
    """Make the paper's controller, at each turn from dilating to contracting, pause for ``hold`` of its
    updates (one a step) with only the band's lights beside the ``chosen`` sides lit; the count of turns so
    far."""
    controller, keep = sim.controller, beside(sim, chosen)
    advance = controller.update
    state = {"phase": controller.state.phase, "held": 0, "turns": 0}

    def update(observation):
        if state["held"] > 0:
            state["held"] -= 1
            return controller.intensities if state["held"] == 0 else None  # the band again, where it was
        pattern = advance(observation)
        now, before = controller.state.phase, state["phase"]
        state["phase"] = now
        if before.startswith("dilat") and now.startswith("contr"):
            state["held"], state["turns"] = hold, state["turns"] + 1
            return controller.intensities * keep
        return pattern

    controller.update = update
    return state


def trial(args: tuple[str, int, int, str, str, int]) -> tuple[int, int, float, float]:
    shape, seed, steps, use, sides, hold = args
    sim = Simulation(Config(shape=shape, seed=seed, gather=GATHER))
    x0, _, x1, _ = shapely.Polygon(sim.goal.vertices).bounds
    gathered = gather_at_turns(sim, sides, hold) if use == "gather" else None
    phase, turns, late = sim.controller.state.phase, 0, []
    while sim.steps_done < steps:
        sim.step(100)
        now = sim.controller.state.phase
        if use == "mirror" and phase.startswith("dilat") and now.startswith("contr"):
            mirror_outside(sim, (x0 + x1) / 2)
            turns += 1
        phase = now
        if sim.steps_done >= 0.8 * steps and sim.steps_done % 1000 == 0:
            late.append(sim.measure().fraction_in_goal)
    if gathered is not None:
        turns = gathered["turns"]
    return seed, turns, sim.measure().fraction_in_goal, float(np.mean(late))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("use", choices=("count", "mirror", "gather", "mouths"))
    parser.add_argument("shape")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3])
    parser.add_argument("--steps", type=int)
    parser.add_argument("--no-mirror", action="store_true")
    parser.add_argument("--sides", default="L", help="gather: the sides to gather beside (any of L, R, B, T)")
    parser.add_argument("--hold", type=int, default=3000, help="gather: steps the band is held at each turn")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    try:
        vertices = shape_vertices(args.shape)
    except ShapeError as exc:
        parser.error(str(exc))
    if vertices is None:
        parser.error(f"{args.shape} is a circle: it has no sides or notches to look at; give a polygon")
    if args.steps is not None and (args.steps < 1000 or args.steps % 1000):
        parser.error(f"--steps must be a positive multiple of 1,000 (counts and the last fifth's mean are taken "
                     f"every 1,000 steps), not {args.steps}")
    if args.workers < 1:
        parser.error(f"--workers must be at least 1, not {args.workers}")
    if args.use == "mouths":
        mouths(args.shape)
        return
    if args.use == "count":
        count(args.shape, args.seed, args.steps or 60_000)
        return
    if args.use == "gather" and (not args.sides or set(args.sides) - set("LRBT") or args.hold < 1):
        parser.error("gather needs --sides made of L, R, B and T, and --hold of at least 1 step")
    use = "none" if args.no_mirror else args.use
    jobs = [(args.shape, seed, args.steps or 100_000, use, args.sides, args.hold) for seed in args.seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(trial, jobs))
    for seed, turns, last, late in results:
        what = "left alone" if use == "none" else use
        print(f"seed {seed}: {turns} turns {what}, {last:.3f} at the last step, {late:.3f} over the last fifth")
    for name, values in (("last step", [r[2] for r in results]), ("last fifth", [r[3] for r in results])):
        v = np.array(values)
        error = v.std(ddof=1) / math.sqrt(len(v)) if len(v) > 1 else float("nan")
        print(f"{name}: {v.mean():.3f} ± {error:.3f}")


if __name__ == "__main__":
    main()
