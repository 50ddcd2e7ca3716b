"""Which settings a crashed simulation is started again from (sandbox.app.world.standing), issue 54 B.

Settings that killed the simulation process were restarted from as they were, and killed it again every
15-20 s for as long as the server ran. Here the rule alone, without processes: what stands, what a crash
goes back to, when the count of crashes starts again, and the line the page is told (pinned by hand)."""

from __future__ import annotations

import numpy as np

from sandbox.app.world.standing import Settings, Standing, changed, gone_back, values
from sandbox.model.config import Config

FIRST = Settings(Config(), "from-config", None)
DENSE = Settings(Config(light_pitch=0.5, field_samples=64), "from-config", None)
BIGGER = Settings(Config(robots=300), "from-config", 4)
KILLED = "the simulation process was killed, most likely out of memory (exit code -9)"


def test_values_are_named_plainly_and_at_most_four_of_them():
    assert values(Config(light_pitch=0.5, field_samples=64), ["light_pitch", "field_samples"]) == \
        "light pitch 0.5, field samples 64"
    names = changed(Config(profile="paper-text"), Config())
    assert len(names) == 23 and names[:2] == ["profile", "assembly_centre"]
    assert values(Config(profile="paper-text"), names) == \
        "profile paper-text, assembly centre arena, box size is apothem, box skin 0, 19 more"


def test_a_seed_does_not_make_settings_new_but_a_goal_does():
    assert Settings(Config(seed=3), "from-config", 3).same_world(FIRST)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert not Settings(Config(), square, None).same_world(FIRST)
    assert Settings(Config(), square.copy(), None).same_world(Settings(Config(), square, None))
    assert not Settings(Config(), square[:3], None).same_world(Settings(Config(), square, None))


def test_the_page_is_told_which_values_failed_and_which_stand():
    assert gone_back(KILLED, DENSE, FIRST) == (
        "the simulation process was killed, most likely out of memory (exit code -9) with light pitch 0.5, "
        "field samples 64; back to the last settings that ran (light pitch 1, field samples 6)")
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert gone_back("it stopped", Settings(Config(), square, None), FIRST) == \
        "it stopped with another goal; back to the last settings that ran"


def test_a_crash_with_new_settings_goes_back_to_those_that_ran_at_once():
    standing = Standing(FIRST)
    restart = standing.crashed(DENSE)
    assert restart.went_back and restart.settings is FIRST
    assert standing.crashed(DENSE).settings is FIRST  # and again, never from the settings that failed
    assert standing.crashes == 2


def test_a_crash_with_the_settings_that_stand_restarts_from_them_then_goes_back_further():
    standing = Standing(FIRST)
    standing.ran(BIGGER)
    assert standing.settings is BIGGER and standing.crashes == 0
    running = Settings(BIGGER.config.replace(seed=9), "from-config", 9)  # the running world's seed is kept
    first = standing.crashed(running)
    assert not first.went_back and first.settings is running
    second = standing.crashed(running)  # a second crash with the same settings: those that ran before
    assert second.went_back and second.settings is FIRST and standing.settings is FIRST
    third = standing.crashed(FIRST)  # nothing older: the first settings again, counted
    assert not third.went_back and third.settings is FIRST and standing.crashes == 3


def test_the_crashes_are_counted_from_the_last_world_that_ran():
    standing = Standing(FIRST)
    for count in (1, 2, 3):
        standing.crashed(DENSE)
        assert standing.crashes == count
    standing.ran(FIRST)
    assert standing.crashes == 0
    standing.crashed(FIRST)
    assert standing.crashes == 1


def test_settings_that_ran_again_move_to_the_top_and_four_are_kept():
    standing = Standing(FIRST)
    ran = [Settings(Config(robots=n), "from-config", None) for n in (201, 202, 203, 204)]
    for settings in ran:
        standing.ran(settings)
    standing.ran(Settings(Config(robots=202), "from-config", 5))
    assert [s.config.robots for s in standing._ran] == [201, 203, 204, 202]
    assert standing.settings.seed == 5
