"""When a batch of trials will be done: :class:`Pace`, the time left of trials that a few worker
processes take in order, from what the trials done so far cost, and :func:`in_words`.

Each trial belongs to a *group* (the advice: a candidate, whose seeds cost about the same) and a
*kind* (the advice: chase or an open loop), and has a *weight*, its steps times what a step of its
kind costs relative to the other (the advice's chase trials cost about twice an open loop's step for
step: ``advise.CHASE_COST``). A trial is expected to take what the trials of its group done so far
took; one of a group not yet seen, its weight at the seconds per unit of weight of all the trials done
so far. There is no estimate until a trial of each kind is done: before, one kind's cost would be
guessed from the other's (on the letter E a first estimate from chase alone ran 42 % short; 31 % once
one of each was done). The trials still to run are laid out on the workers as the pool takes them (in
order, each to the first worker free), each running trial counted for the time it has run. So the
estimate follows the *steps* left, not the count of trials, and a batch whose last trials are long
(or short) is not misjudged.
"""

from __future__ import annotations

import heapq
from typing import Sequence


class Pace:
    """The time left of ``weights`` (one per trial, in the order the pool takes them) on ``workers``
    workers that started at ``started`` (any clock: seconds); ``groups`` (one per trial): trials that
    cost alike (default: each its own); ``kinds`` (one per trial): trials whose cost per unit of weight
    is alike (default: all one kind)."""

    def __init__(self, weights: Sequence[float], workers: int, started: float, groups: Sequence | None = None,
                 kinds: Sequence | None = None):
        self.weights = [float(w) for w in weights]
        self.groups = list(range(len(self.weights))) if groups is None else list(groups)
        self.kinds = [None] * len(self.weights) if kinds is None else list(kinds)
        self.workers = max(1, int(workers))
        #: When each trial began (None: not yet): the first ``workers`` at once, then one at each finish.
        self.began: list[float | None] = [None] * len(self.weights)
        self.finished: dict[int, float] = {}  # trial -> the seconds it took
        for index in range(min(self.workers, len(self.weights))):
            self.began[index] = started

    def done(self, index: int, seconds: float, now: float) -> None:
        """Trial ``index`` finished at ``now`` after ``seconds`` of running; its worker takes the next."""
        self.finished[index] = float(seconds)
        waiting = next((i for i, began in enumerate(self.began) if began is None), None)
        if waiting is not None:
            self.began[waiting] = now

    @property
    def seconds_per_weight(self) -> float | None:
        """What a unit of weight took, over the trials done (None before the first)."""
        weight = sum(self.weights[i] for i in self.finished)
        return sum(self.finished.values()) / weight if weight > 0 else None

    def expected(self, index: int, pace: float) -> float:
        """The seconds trial ``index`` should take: as its group's done so far, else by its weight."""
        seen = [seconds for i, seconds in self.finished.items() if self.groups[i] == self.groups[index]]
        return sum(seen) / len(seen) if seen else pace * self.weights[index]

    def seconds_left(self, now: float) -> float | None:
        """Until the last trial is done (None until a trial of each kind is done: no pace to go by)."""
        pace = self.seconds_per_weight
        if pace is None or {self.kinds[i] for i in self.finished} != set(self.kinds):
            return None
        free = []  # when each worker is free: running trials end when expected, at the least now
        for index, began in enumerate(self.began):
            if began is not None and index not in self.finished:
                free.append(now + max(self.expected(index, pace) - (now - began), 0.0))
        free += [now] * (self.workers - len(free))
        heapq.heapify(free)
        for index, began in enumerate(self.began):
            if began is None:
                heapq.heapreplace(free, free[0] + self.expected(index, pace))
        return max(free) - now


def in_words(seconds: float | None) -> str:
    """'about 2 min 10 s left'; None: no pace yet."""
    if seconds is None:
        return "time left: known once the first trials are done"
    seconds = round(seconds)
    if seconds >= 60:
        minutes, seconds = divmod(seconds, 60)
        return f"about {minutes} min {seconds} s left" if minutes < 10 else f"about {minutes} min left"
    return f"about {max(seconds, 1)} s left"
