"""Be the light (issue 25, item 2): a lamp a person moves, as a light program."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.lamp import LARGEST_RADIUS, SMALLEST_RADIUS, Lamp
from sandbox.model.programs import Observation


def observation(config: Config) -> Observation:
    n, pitch = config.lights_per_side, config.light_pitch
    centres = (np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), axis=-1) + 0.5) * pitch
    return Observation(step=0, goal=None, light_centres=centres,
                       intensities=np.zeros((n, n)), senses=frozenset(), _read=lambda what: None)


def test_the_lamp_lights_the_disc_about_where_it_was_aimed():
    config = Config()  # 64 x 64 lights, 1 m apart, centres at 0.5, 1.5, ...
    obs = observation(config)
    lamp = Lamp(radius=1.0)
    lamp.reset(config, None)
    assert lamp.update(obs).sum() == 0  # dark until aimed
    assert lamp.update(obs) is None  # and then nothing new
    lamp.aim(10.5, 20.5)
    on = lamp.update(obs)
    # Radius 1 about a light's centre: that light and its 4 neighbours, 1 m away.
    assert on.sum() == 5 and on[10, 20] == 1 and on[9, 20] == on[11, 20] == on[10, 19] == on[10, 21] == 1
    assert lamp.update(obs) is None  # unmoved: the pattern stays
    lamp.aim(10.5, 20.5, radius=1.5)  # the 4 diagonal neighbours too, sqrt(2) = 1.41 m away
    assert lamp.update(obs).sum() == 9
    lamp.aim(0.0, 0.0, radius=1.0)  # the arena's corner: the one light within 1 m, 0.71 m away
    assert lamp.update(obs).sum() == 1


def test_a_brush_paints_and_erases_lights_keeping_the_others():
    config = Config()
    obs = observation(config)
    lamp = Lamp(radius=1.0)
    lamp.reset(config, None)
    lamp.aim(10.5, 20.5, mode="paint")  # 5 lights (as above)
    lamp.aim(30.5, 30.5, mode="paint")  # 5 more, far away
    on = lamp.update(obs)
    assert on.sum() == 10 and on[10, 20] == on[30, 30] == 1
    lamp.aim(10.5, 20.5, mode="erase")
    on = lamp.update(obs)
    assert on.sum() == 5 and on[10, 20] == 0 and on[30, 30] == 1
    lamp.reset(config, None)  # a new world keeps what was painted
    assert lamp.update(obs).sum() == 5
    lamp.aim(0.0, 0.0)  # the lamp again: only its own lights
    assert lamp.update(obs).sum() == 1
    with pytest.raises(ValueError, match="unknown mode"):
        lamp.aim(1.0, 1.0, mode="flood")


def test_the_lamp_radius_stays_within_what_the_page_offers():
    lamp = Lamp()
    lamp.aim(5.0, 5.0, radius=0.01)
    assert lamp.radius == SMALLEST_RADIUS
    lamp.aim(5.0, 5.0, radius=1e9)
    assert lamp.radius == LARGEST_RADIUS


def test_the_runner_hands_the_lights_to_the_lamp_and_back():
    from sandbox.app.world.runner import Runner
    from sandbox.app.world.orders import SetLamp
    from sandbox.app.world.snapshot import LAMP_PROGRAM, PAPER_PROGRAM
    from tests.waiting import wait_until

    config = Config(robots=20, boxes=30)
    runner = Runner(config, fps=60, steps_per_frame=5)
    runner.start()
    try:
        centre = (20.5, 40.5)
        runner.ask(SetLamp(centre, 3.0))
        wait_until(lambda: runner.latest.program == LAMP_PROGRAM and runner.latest.intensities.any(),
                   what="the lamp's lights")
        lit = np.argwhere(runner.latest.intensities > 0) + 0.5  # light centres (1 m pitch)
        assert np.hypot(*(lit - centre).T).max() <= 3.0 and len(lit) >= 25  # 29 lights within 3 m
        step = runner.latest.step
        runner.ask(SetLamp(None))
        wait_until(lambda: runner.latest.program == PAPER_PROGRAM, what="the paper's controller back")
        assert runner.latest.step >= step  # the same world goes on
    finally:
        runner.stop()


@pytest.mark.slow
def test_one_click_brings_robots_to_the_lamp_within_30_s_of_play():
    """The default world, the lamp clicked 6 m outside the construction wall, radius 4 m: within 9,000
    steps (30 s of play at the page's default speed, 300 steps/s) about 30 robots are within 5 m of it,
    every one of them charged. Measured on seeds 0, 1, 2: 9 -> 30, 20 -> 36, 12 -> 29 (seed 0 here)."""
    seed = 0
    from sandbox.model.simulation import Simulation

    config = Config()
    sim = Simulation(config, seed=seed, open_ended=True)
    lamp = Lamp(radius=4.0)
    sim.use_program(lamp)
    spot = np.array([config.centre - config.construction_size / 2 - 6.0, config.centre])
    lamp.aim(*spot)
    near = lambda: np.hypot(*(sim.robot_positions - spot).T) <= 5.0  # noqa: E731
    before = int(near().sum())
    sim.step(9000)
    after = near()
    assert after.sum() >= 25 and after.sum() >= before + 10
    assert (sim.robot_charges[after] > 0).mean() > 0.9


def test_with_every_light_off_nothing_moves_so_a_round_scores_at_most_its_start():
    """Issue 25, item 3: an honest score. Robots start empty; with no light none charges, so no box
    moves and the share in the goal stays the starting share."""
    from sandbox.model.simulation import Simulation

    config = Config(robots=40, boxes=80)
    sim = Simulation(config, seed=0, open_ended=True)
    lamp = Lamp()
    sim.use_program(lamp)  # never aimed: dark
    start = sim.measure().fraction_in_goal
    sim.step(2000)
    assert sim.measure().fraction_in_goal <= start


def test_a_round_is_scored_against_the_paper_in_the_same_world_and_steps():
    """A round from the page's folder: the player's share at the round's end, and the paper's
    controller's in the same world after the same steps (computed again here, the same number)."""
    from sandbox.commands.serve import App, free_port
    from sandbox.model.challenge import ROUND_SEED, paper_gain
    from tests.waiting import wait_until

    config = Config(robots=40, boxes=80, update_every=20, hold_steps=5)
    app = App(config, port=free_port(), fps=60, steps_per_frame=20, process=False).start()
    try:
        folder = app.panel.challenge
        folder.round_steps = 600
        folder.start("  Ada   Lovelace ", None)
        wait_until(lambda: "Ada Lovelace" in folder.scores.content, timeout=120, what="the round and its reference")
        r = folder.round
        assert r.player == "Ada Lovelace" and r.at_step >= 600 and r.world is not None
        assert r.paper == paper_gain(app.runner.latest.world_config, ROUND_SEED, r.at_step, None)
        assert folder.best == {"Ada Lovelace": r.score.share}
        assert "Ada Lovelace" in folder.scores.content and "paper's controller" in folder.status.content
        assert not app.runner.playing  # the round's end waits
    finally:
        app.stop()


def test_stopping_the_app_ends_a_reference_run_at_once():
    """The reference run's pool is the event thread's once a worker started it: the app's stop, an event,
    terminates it there, and the round counts without a reference."""
    from sandbox.app.panel.challenge import ChallengeFolder, Round
    from sandbox.app.web.events import EventQueue
    from sandbox.model.challenge import Gain
    from tests.waiting import wait_until

    class Markdown:
        content = ""

    events = EventQueue().open()
    try:
        folder = ChallengeFolder(gui=None, runner=None, lockstep=None, lamp=None, on_change=lambda what: None,
                                 events=events)
        folder.status, folder.scores = Markdown(), Markdown()
        r = Round("Ada", 10**9, 0, world=1, score=Gain(20, 40, 80), at_step=10**9)  # a reference for days
        events.call(folder._score_the_paper, r, (Config(robots=20, boxes=30), 0, None))
        wait_until(lambda: events.call(lambda: bool(folder._pools)), timeout=20, what="the pool handed over")
        pool = events.call(lambda: next(iter(folder._pools)))
        # The worker that started it ends once it handed the pool over (it may still be leaving on a busy machine).
        wait_until(lambda: not any(thread.is_alive() for thread in folder._starters), timeout=20,
                   what="the pool's starter to end")
        assert events.call(folder.stop) == []
        assert "no reference" in folder.status.content and pool._state == "TERMINATE"
        assert folder.best == {"Ada": 1 / 3} and r.paper is None
    finally:
        events.stop()
