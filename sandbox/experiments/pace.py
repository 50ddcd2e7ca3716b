"""When a batch of trials will be done: :class:`Pace`, the time left of trials that a few worker
processes take in order, from what the trials done so far cost, and :func:`in_words`.

Each trial belongs to a *group* (the advice: a candidate, whose seeds cost about the same) and a
*kind* (the advice: an outline family with chase or with an open loop), and has a *weight*, its steps times what a step of its
kind costs relative to the other (the advice's chase trials cost about twice an open loop's step for
step: ``advise.CHASE_COST``). A trial is expected to take what the trials of its group done so far
took; one of a group not yet seen, its weight at the seconds per unit of weight of the trials of its
kind done so far (a chase trial's cost is not guessed from an open loop's). There is no estimate until
a trial of each kind is done: before, one kind's cost would be guessed from the other's (on the letter E
a first estimate from chase alone ran 42 % short; 31 % once one of each was done, both kinds at one
pace). The trials still to run are laid out on the workers as the pool takes them (in
order, each to the first worker free), each running trial counted for the time it has run. So the
estimate follows the *steps* left, not the count of trials, and a batch whose last trials are long
(or short) is not misjudged.

The machine's speed changes while the trials run (the page's live simulation needs from a third of a
core to a whole one as its boxes pack; other work comes and goes): a trial whose group ran before tells
how fast trials run *now* against then, its seconds over its group's earlier ones, and every trial not
yet done is expected to take that much of what it would have (the mean of the :data:`RECENT` latest such
ratios). On the page's advisor for the L the second seeds took half their first's as the machine's load
fell, and the time left ran up to twice what was left without it. One ratio alone is not taken for a
change of speed (:data:`FEWEST_RATIOS`): a single seed's cost differs from its group's first by a third
or more on a machine whose speed did not change.
"""

from __future__ import annotations

import heapq
from typing import Sequence

#: How many of the latest trials whose group ran before set the speed now (a few: one seed's cost differs
#: from another's by a third or more).
RECENT = 4

#: How many such ratios it takes before the speed now is believed. On a quiet machine the arrow's first
#: ratio was one seed's noise (1.36: its second chase seed took 6.1 s after 4.5 s; the next ratios were
#: 0.92 and 0.71), and scaling everything left by it put the time left 57-66 % over with 10 s left; with
#: two, 16 %. On 8 runs recorded under a changing load (the L and the star, 25-450 s), where no rule kept
#: within 30 %, the share of the time shown more than 30 % off grew by 0 (5 runs) to 5 and 13 points.
FEWEST_RATIOS = 2


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
        #: Each trial whose group ran before, in the order they finished: its seconds over its group's before.
        self.ratios: list[float] = []
        for index in range(min(self.workers, len(self.weights))):
            self.began[index] = started

    def done(self, index: int, seconds: float, now: float) -> None:
        """Trial ``index`` finished at ``now`` after ``seconds`` of running; its worker takes the next."""
        before = self._group_seconds(index)
        if before:
            self.ratios.append(float(seconds) / before)
        self.finished[index] = float(seconds)
        waiting = next((i for i, began in enumerate(self.began) if began is None), None)
        if waiting is not None:
            self.began[waiting] = now

    def seconds_per_weight(self, kind: object = None) -> float | None:
        """What a unit of weight took, over the trials of ``kind`` done (None before the first)."""
        done = [i for i in self.finished if self.kinds[i] == kind]
        weight = sum(self.weights[i] for i in done)
        return sum(self.finished[i] for i in done) / weight if weight > 0 else None

    def _group_seconds(self, index: int) -> float | None:
        """What the trials done of ``index``'s group took, on average (None: none done)."""
        seen = [seconds for i, seconds in self.finished.items() if self.groups[i] == self.groups[index]]
        return sum(seen) / len(seen) if seen else None

    @property
    def speed(self) -> float:
        """How long trials take now against before: the mean of the :data:`RECENT` latest ratios (1: fewer
        than :data:`FEWEST_RATIOS`)."""
        recent = self.ratios[-RECENT:]
        return sum(recent) / len(recent) if len(recent) >= FEWEST_RATIOS else 1.0

    def expected(self, index: int) -> float:
        """The seconds trial ``index`` should take: as its group's done so far, else by its weight at its
        kind's pace; at the speed now."""
        seen = self._group_seconds(index)
        base = seen if seen is not None else self.seconds_per_weight(self.kinds[index]) * self.weights[index]
        return base * self.speed

    def seconds_left(self, now: float) -> float | None:
        """Until the last trial is done (None until a trial of each kind is done: no pace to go by)."""
        if {self.kinds[i] for i in self.finished} != set(self.kinds):
            return None
        free = []  # when each worker is free: running trials end when expected, at the least now
        for index, began in enumerate(self.began):
            if began is not None and index not in self.finished:
                free.append(now + max(self.expected(index) - (now - began), 0.0))
        free += [now] * (self.workers - len(free))
        heapq.heapify(free)
        for index, began in enumerate(self.began):
            if began is None:
                heapq.heapreplace(free, free[0] + self.expected(index))
        return max(free) - now


#: Under this many seconds (estimated) no figure is said, only "a few seconds left": the last trials end a
#: few seconds either side of their estimate, most of what is left then, and a figure would be off by more
#: than the 30 % it may be (issue 56). Chosen on the page's advisor on the star on a quiet machine (said
#: 10-12 s with 7.4-9.8 s left: 25-37 % off; from 15 s up at most 28 %), checked on the arrow and the T.
A_FEW_SECONDS = 15.0


def in_words(seconds: float | None) -> str:
    """The time left as a figure no finer than the estimate can back: 'a few seconds left' under
    :data:`A_FEW_SECONDS`, whole seconds under half a minute, then to 5 s, from a minute to 10 s
    ('about 2 min 10 s left'), from 10 minutes whole minutes; None: no pace yet."""
    if seconds is None:
        return "time left: known once the first trials are done"
    if seconds < A_FEW_SECONDS:
        return "a few seconds left"
    step = 1 if seconds < 30 else 5 if seconds < 60 else 10 if seconds < 600 else 60
    seconds = int((seconds + step / 2) // step * step)  # to the nearest step, halves up
    if seconds >= 60:
        minutes, seconds = divmod(seconds, 60)
        return f"about {minutes} min {seconds} s left" if minutes < 10 else f"about {minutes} min left"
    return f"about {seconds} s left"
