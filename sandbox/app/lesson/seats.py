"""The class's seats: each student's identity, issued by the server, and whose it is.
Issued and checked on viser's event loop (the gate's handshakes); read on the app's event thread.

A seat's identity is ``secrets.token_urlsafe(24)`` (192 random bits), made here as a page asks the
students' link, and bound to the address that asked (its :func:`~sandbox.app.web.access.address_group`):
a page from another address cannot take it. It is the page's address (``/seat/<identity>``), so a
student who reloads finds their world again; the gate lets one page at a time hold it.
"""

from __future__ import annotations

import itertools
import secrets
import threading
import time
from dataclasses import dataclass

from sandbox.app.web.access import address_group

#: Seats the class holds in all, and from one address (a school's network may show every student
#: under one address): past these, the students' link answers that the class is full.
MOST_SEATS = 40
MOST_SEATS_PER_ADDRESS = 40
#: A seat whose page never connected is given back after this long (s): a student who opens the
#: students' link again and again takes one seat, not the class's.
UNCLAIMED_SECONDS = 120.0


@dataclass
class Seat:
    """One student's place: the identity, the address group it was issued to, and its label."""

    identity: str
    group: str
    number: int
    label: str = ""
    issued: float = 0.0  # time.monotonic() when issued
    claimed: bool = False  # a page connected to it (its world is made): it is kept


class Seats:
    """Every seat issued (the gate's :class:`~sandbox.app.web.access.Seats`)."""

    def __init__(self, most: int = MOST_SEATS, most_per_address: int = MOST_SEATS_PER_ADDRESS):
        self.most, self.most_per_address = int(most), int(most_per_address)
        self._seats: dict[str, Seat] = {}
        self._numbers = itertools.count(1)
        # Shared by viser's event loop (issuing and checking at each handshake) and the app's event
        # thread (finding a page's seat, listing the class for the wall).
        self._lock = threading.Lock()

    def issue(self, address: str, now: float | None = None) -> str | None:
        group = address_group(address)
        now = time.monotonic() if now is None else now
        with self._lock:
            for identity in [i for i, seat in self._seats.items()
                             if not seat.claimed and now - seat.issued > UNCLAIMED_SECONDS]:
                del self._seats[identity]  # never used: its place goes back to the class
            if len(self._seats) >= self.most:
                return None
            if sum(seat.group == group for seat in self._seats.values()) >= self.most_per_address:
                return None
            identity = secrets.token_urlsafe(24)
            number = next(self._numbers)
            self._seats[identity] = Seat(identity, group, number, f"Student {number}", issued=now)
            return identity

    def claim(self, identity: str) -> None:
        """A page connected to the seat (on the event thread): it is kept from now on."""
        with self._lock:
            seat = self._seats.get(identity)
            if seat is not None:
                seat.claimed = True

    def check(self, identity: str, address: str) -> str:
        with self._lock:
            seat = self._seats.get(identity)
        if seat is None:
            return "no such seat"
        if seat.group != address_group(address):
            return "this seat was given to another address"
        return ""

    def get(self, identity: str) -> Seat | None:
        with self._lock:
            return self._seats.get(identity)

    def all(self) -> list[Seat]:
        with self._lock:
            return sorted(self._seats.values(), key=lambda seat: seat.number)
