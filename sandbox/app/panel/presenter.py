"""The presenter's screen (issue 41, items 2 and 3): what a page shows on the
floor's side of the panel, for a room. Runs on the app's event thread.

- **The title card.** A page that arrives while the world waits at step 0
  (``serve --classroom`` or ``--paused``: a class before the lesson starts)
  gets a card of three lines: what the class is looking at, what to watch
  for, and "press Play (space)" ("tap Play" on a touch screen or at a
  phone's width: the page's layout script, :mod:`sandbox.app.web.page_layout`,
  swaps the words). Any page's Play (the card's, the bar's, the panel's or
  the space key) closes every page's card. It is a viser modal: it
  has no close button of its own (viser closes modals from the server only),
  so a watching page, which cannot press Play, keeps it until the presenter
  does, and its third line says so.
- **The on-screen bar.** Each controlling page in the presenter layout (its
  panel folded to a thin bar) gets Play, Pause, Step and Reset in a small
  panel floating over the canvas's bottom-left corner, where the floor is
  empty in every framing. Real viser controls: the gate checks each click
  as it checks the panel's.
- **Joining mid-run.** A page that may control the simulation and arrives
  when the run is far along (:data:`OFFER_FROM_STEP`), the server having
  shown it to an earlier page, is offered *Start over* (a reset with the
  same seed: the same run again from its start) in a floating panel at the
  canvas's bottom right, which goes away after two minutes or when answered.
  The server's first page is not joining anything: whoever just typed
  ``phototaxis`` sees the run the server began for them. The offer names no
  step: it stays two minutes while the run goes on (a number in it went
  stale beside the caption's). A watching page gets nothing: it just watches.

"First visit" is read as "arrives while the world has not been played yet":
viser gives the server no cookies, so a page cannot be told from one that
came before, and a card on every page at step 0 is what a class needs (the
projector, and each student's page, before the lesson starts).

Every button here acts through the Run folder's own actions, on the app's
event thread.
"""

from __future__ import annotations

from typing import Any, Callable

import viser

from sandbox.app.web.page_layout import PRESS_PLAY
from sandbox.app.panel.plain import plain
from sandbox.app.world.snapshot import Snapshot, case_name

#: How long the Start over offer stays (s): a loaded classroom laptop may take half a minute to show it.
OFFER_SECONDS = 120.0
#: A run is far along enough to offer Start over from this step on: about 7 s at the default pace (750
#: steps a second), past the band's first sweep that a page arriving earlier hardly missed.
OFFER_FROM_STEP = 5_000
#: The on-screen bar's and the offer's width (CSS px): buttons large enough to hit on a projector.
BAR_WIDTH, OFFER_WIDTH = 210.0, 300.0
#: Their gap to the canvas's edges (CSS px).
EDGE = 15.0


def title_lines(snap: Snapshot, compared: Snapshot | None, controls: bool) -> tuple[str, str, str]:
    """The title card's three lines: what the class is looking at, what to watch for, what to do."""
    cfg = snap.world_config
    if compared is None:
        looking = (f"{cfg.robots} robots that only drive towards light push {cfg.boxes} boxes into a "
                   f"{plain(snap.shape_name)}.")
        watch = "Watch the yellow band shrink: the robots ride it and push the boxes into the goal (pink)."
    else:
        looking = (f"The same start twice: {plain(case_name(snap.shape_name, snap.strategies))} and "
                   f"{plain(case_name(compared.shape_name, compared.strategies))}.")
        watch = "Watch which one gets more boxes into its goal: the large share under each."
    act = f"**{PRESS_PLAY}**" if controls else "The presenter starts it with Play."  # a touch page taps
    return looking, watch, act


class PresenterScreen:
    """Each page's title card, on-screen bar and Start over offer (see the module docstring)."""

    def __init__(self, runner: Any, lockstep: Any, run: Any, compared: Callable[[], Any], *, events: Any):
        """``run``: the Run folder, whose play, pause, step and reset these buttons are; ``compared()``:
        compare mode's second runner, or None; ``events``: the app's event queue (its timers)."""
        self.runner, self.lockstep, self.run, self._compared, self._events = runner, lockstep, run, compared, events
        self.controls: dict[int, bool] = {}
        self.cards: dict[int, Any] = {}
        self.bars: dict[int, Any] = {}
        #: per page offered Start over: the offer's panel, and the world it offers to start over
        self.offers: dict[int, tuple[Any, int]] = {}
        #: Whether a page came before (the server's first page joins nothing: the run began for it).
        self.seen_a_page = False

    # The panel builds and refreshes every folder; this one has nothing in the shared panel.
    def build(self, snap: Snapshot) -> None:
        """Nothing in the shared panel: everything here is a page's own."""

    def update(self, snap: Snapshot) -> None:
        """Playing: no title card is left (Play may have come from any page, or a key). A new world: no
        offer to start the old one over is left (a designer's goal used, a reset from any page)."""
        if snap.playing and self.cards:
            self.close_cards()
        for client_id, (_, world) in list(self.offers.items()):
            if world != snap.world_key:
                self._withdraw(client_id)

    # ------------------------------------------------------------ pages
    def arrive(self, client: Any, controls: bool) -> None:
        """A page connected: its title card at step 0, or its Start over offer when it joins a run that an
        earlier page saw and that is far along."""
        self.controls[client.client_id] = controls
        snap = self.runner.latest
        joins = self.seen_a_page and snap.step >= OFFER_FROM_STEP
        self.seen_a_page = True
        if snap.step == 0 and not self.lockstep.playing:
            self.show_card(client, controls)
        elif controls and joins:
            self.offer_start_over(client)

    def forget(self, client_id: int) -> None:
        for table in (self.controls, self.cards, self.bars, self.offers):
            table.pop(client_id, None)

    # ------------------------------------------------------------ the title card
    def show_card(self, client: Any, controls: bool) -> None:
        partner = self._compared()
        snap = self.runner.latest
        lines = title_lines(snap, None if partner is None else partner.latest, controls)
        card = client.gui.add_modal(f"Phototaxis: {case_name(snap.shape_name, snap.strategies)}")
        with card:
            client.gui.add_markdown("  \n".join(lines))
            if controls:
                play = client.gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY, hint="Start the simulation (space)")
                play.on_click(lambda event: self.play())
        self.cards[client.client_id] = card

    def close_cards(self) -> None:
        cards, self.cards = self.cards, {}
        for card in cards.values():
            try:
                card.close()
            except Exception:  # noqa: BLE001 - the page has left
                pass

    # ------------------------------------------------------------ the bar
    def presenting(self, client: Any, shown: bool) -> None:
        """A page entered (``shown``) or left the presenter layout: its on-screen bar, if it controls."""
        bar = self.bars.pop(client.client_id, None)
        if bar is not None:
            bar.remove()
        if shown and self.controls.get(client.client_id, False):
            self.bars[client.client_id] = self._add_bar(client)

    def _add_bar(self, client: Any) -> Any:
        panel = client.gui.add_panel()
        with panel.add_tab("Run", viser.Icon.PLAYER_PLAY):
            buttons = (("Play", viser.Icon.PLAYER_PLAY, "Start the simulation (space)", self.play),
                       ("Pause", viser.Icon.PLAYER_PAUSE, "Stop the simulation (space)", self.pause),
                       ("Step", viser.Icon.PLAYER_TRACK_NEXT, "One controller update (s)", self.run.step),
                       ("Reset", viser.Icon.REFRESH, "The same run again from step 0 (r)",
                        lambda: self.run.reset(client)))
            for label, icon, hint, action in buttons:
                client.gui.add_button(label, icon=icon, hint=hint).on_click(lambda event, action=action: action())
        panel.float(x=EDGE, y=-EDGE, width=BAR_WIDTH)
        return panel

    # ------------------------------------------------------------ joining mid-run
    def offer_start_over(self, client: Any) -> None:
        panel = client.gui.add_panel()
        with panel.add_tab("Joining mid-run", viser.Icon.PLAYER_SKIP_BACK):
            # No step number: the offer stays while the run goes on (the caption says the step).
            client.gui.add_markdown("This run began before you came. See it from the start?")
            start = client.gui.add_button("Start over", icon=viser.Icon.PLAYER_SKIP_BACK,
                                          hint="The same run again from step 0 (the same seed), for every page")
            keep = client.gui.add_button("Go on from here", icon=viser.Icon.X)
        start.on_click(lambda event: (self._withdraw(client.client_id), self.run.reset(client)))
        keep.on_click(lambda event: self._withdraw(client.client_id))
        panel.float(x=-EDGE, y=-EDGE, width=OFFER_WIDTH)
        self.offers[client.client_id] = (panel, self.runner.latest.world_key)
        self._events.after(OFFER_SECONDS, self._withdraw, client.client_id)

    def _withdraw(self, client_id: int) -> None:
        offer = self.offers.pop(client_id, None)
        if offer is not None:
            offer[0].remove()

    # ------------------------------------------------------------ actions
    def play(self) -> None:
        self.lockstep.set_playing(True)
        self.run.sync_play_button()
        self.close_cards()

    def pause(self) -> None:
        self.lockstep.set_playing(False)
        self.run.sync_play_button()
