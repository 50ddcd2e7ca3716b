"""The presenter's screen (issue 41, items 2-3), with stand-in pages: the title card at step 0, closed by
any Play; the on-screen bar for a controlling page in the presenter layout; Start over offered to a
controlling page that arrives mid-run, never to a watcher."""

from __future__ import annotations

from types import SimpleNamespace
from unittest import mock

from sandbox.app.panel.framing import CONSTRUCTION, PRESENTER, Framing
from sandbox.app.panel.presenter import PresenterScreen, title_lines
from sandbox.model.config import Config
from tests.inline_events import InlineEvents


class World:
    """A runner and lockstep stand-in: a step, playing or not."""

    def __init__(self, step: int, playing: bool):
        config = Config()
        self.playing = playing
        self.latest = SimpleNamespace(step=step, playing=playing, world_config=config, shape_name="star",
                                      strategies={}, world_key=0)

    def set_playing(self, playing: bool) -> None:
        self.playing = self.latest.playing = playing


def page(client_id: int):
    client = mock.MagicMock(name=f"page {client_id}")
    client.client_id = client_id
    client.camera.aspect = 1.33
    return client


def screen(step: int, playing: bool):
    world = World(step, playing)
    run = mock.MagicMock(name="the Run folder")
    return PresenterScreen(world, world, run, compared=lambda: None, events=InlineEvents()), world, run


def labels(client) -> list[str]:
    return [call.args[0] for call in client.gui.add_button.call_args_list]


def test_a_page_at_step_0_gets_the_title_card_and_any_play_closes_every_card():
    presenter, world, run = screen(0, playing=False)
    teacher, student = page(1), page(2)
    presenter.arrive(teacher, controls=True)
    presenter.arrive(student, controls=False)
    assert set(presenter.cards) == {1, 2}
    assert labels(teacher) == ["Play"] and labels(student) == []  # a watcher cannot press it
    teacher_text = teacher.gui.add_markdown.call_args.args[0]
    assert teacher_text.count("\n") == 2 and "Press Play (space)" in teacher_text
    assert "presenter starts it" in student.gui.add_markdown.call_args.args[0]
    # Play from anywhere (the space key here): the next frame closes every card.
    world.set_playing(True)
    presenter.update(world.latest)
    assert presenter.cards == {}
    for client in (teacher, student):
        client.gui.add_modal.return_value.close.assert_called_once()
    # The card's own Play plays and closes at once.
    presenter, world, run = screen(0, playing=False)
    teacher = page(1)
    presenter.arrive(teacher, controls=True)
    teacher.gui.add_button.return_value.on_click.call_args.args[0](None)
    assert world.playing and presenter.cards == {}


def test_a_controlling_page_that_arrives_mid_run_is_offered_start_over_a_watcher_is_not():
    presenter, world, run = screen(10_600, playing=True)
    teacher, student = page(1), page(2)
    presenter.arrive(student, controls=False)  # (the server's first page: it joins nothing)
    presenter.arrive(teacher, controls=True)
    assert 1 in presenter.offers and 2 not in presenter.offers and presenter.cards == {}
    assert "Start over" in labels(teacher) and not student.gui.add_panel.called
    start = next(call.args[0] for call, label in zip(teacher.gui.add_button.return_value.on_click.call_args_list,
                                                    labels(teacher)) if label == "Start over")
    start(None)
    run.reset.assert_called_once_with(teacher)  # the same seed: reset(client) with no seed
    assert presenter.offers == {}  # answered: gone


def test_an_offer_to_start_over_goes_when_a_new_world_starts():
    # A designer arriving mid-run who uses a drawn goal instead: the new world is at step 0, and the offer
    # about the old run (in the designer's loop, over the arena's lower right for the whole minute) goes.
    presenter, world, run = screen(12_450, playing=True)
    designer = page(1)
    presenter.seen_a_page = True  # an earlier page saw the run
    presenter.arrive(designer, controls=True)
    presenter.update(world.latest)  # the same world's next frame: it stays
    assert 1 in presenter.offers
    world.latest = SimpleNamespace(**{**vars(world.latest), "step": 0, "world_key": 1})
    presenter.update(world.latest)
    assert presenter.offers == {}
    designer.gui.add_panel.return_value.remove.assert_called_once()


def test_the_bar_is_on_a_controlling_presenter_page_only():
    presenter, world, run = screen(500, playing=True)
    framing = Framing(mock.MagicMock(latest=world.latest), CONSTRUCTION, on_presenter=presenter.presenting)
    teacher, student = page(1), page(2)
    presenter.arrive(teacher, controls=True)
    presenter.arrive(student, controls=False)
    for client in (teacher, student):
        framing.choose(client, PRESENTER)
    assert set(presenter.bars) == {1}
    assert labels(teacher)[-4:] == ["Play", "Pause", "Step", "Reset"]
    clicks = [call.args[0] for call in teacher.gui.add_button.return_value.on_click.call_args_list[-4:]]
    clicks[1](None)
    assert not world.playing
    clicks[2](None)
    run.step.assert_called_once()
    clicks[3](None)
    run.reset.assert_called_with(teacher)
    clicks[0](None)
    assert world.playing
    framing.choose(teacher, CONSTRUCTION)
    assert presenter.bars == {}
    teacher.gui.add_panel.return_value.remove.assert_called()


def test_the_title_card_says_what_the_class_sees_in_three_lines():
    snap = World(0, False).latest
    looking, watch, act = title_lines(snap, None, controls=True)
    assert "200 robots" in looking and "500 boxes" in looking and "star" in looking
    assert "yellow band" in watch and "Play (space)" in act
    looking, watch, _ = title_lines(snap, snap, controls=False)
    assert looking.startswith("The same start twice") and "which one" in watch


def test_the_servers_first_page_and_a_run_just_begun_get_no_offer_and_an_offer_names_no_step():
    """Issue 56, item 12: whoever just typed `phototaxis` was told they were joining a run they never saw,
    and the offer's step (10,275) went stale beside the caption's (13,400)."""
    presenter, world, run = screen(30_000, playing=True)
    first, early, late = page(1), page(2), page(3)
    presenter.arrive(first, controls=True)  # the server's first page, however far the run
    assert presenter.offers == {}
    world.latest.step = 4_999  # a second page, the run just begun: it missed nothing
    presenter.arrive(early, controls=True)
    assert presenter.offers == {}
    world.latest.step = 10_275
    presenter.arrive(late, controls=True)
    assert set(presenter.offers) == {3}
    said = " ".join(call.args[0] for call in late.gui.add_markdown.call_args_list)
    assert "began before you came" in said and not any(ch.isdigit() for ch in said), said
